#pragma once
// Encoding of Cem Yuksel's BCC binary curve collection (see bcc_format.cpp for the layout).
#include <Eigen/Core>
#include <string>
#include <vector>

namespace knit {

/// The bytes of a BCC file holding open polylines (curve type PL, z up). `info` (at most
/// 39 characters are kept) goes into the header's file-info field.
std::string bcc_polylines(const std::vector<Eigen::Matrix3Xd>& curves, const std::string& info);

}  // namespace knit
