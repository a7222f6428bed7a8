#pragma once
// Small states for the io and render tests.
#include <unistd.h>
#include <Eigen/Core>
#include <cmath>
#include <filesystem>
#include <string>

#include "knit/io/state_file.hpp"
#include "knit/spline/fit.hpp"

namespace knit::test {

/// A helix along x (radius `R` cm, `pitch` cm per turn, `turns` turns) fitted with
/// `segments` spline segments, as one yarn of radius r.
inline Eigen::Matrix3Xd helix_control_points(double R = 1.0, double pitch = 1.0, double turns = 3,
                                             int segments = 24) {
  const int n = 400;
  Eigen::Matrix3Xd p(3, n);
  for (int k = 0; k < n; ++k) {
    const double a = 2 * M_PI * turns * k / (n - 1);
    p.col(k) << pitch * a / (2 * M_PI), R * std::cos(a), R * std::sin(a);
  }
  return fit_polyline(p, segments);
}

/// A state of the given yarns (control points, radius r each), time `time`, with stitch
/// rows = segment index / 8 when `stitches` is set.
inline StateFile state_of(const std::vector<Eigen::Matrix3Xd>& yarns, double r = 0.125,
                          double time = 0, bool stitches = false) {
  StateFile f;
  int total = 0;
  for (const auto& y : yarns) total += static_cast<int>(y.cols());
  f.state.q.resize(3 * total);
  f.state.v = Eigen::VectorXd::Zero(3 * total);
  f.state.time = time;
  int at = 0;
  for (const auto& y : yarns) {
    for (int k = 0; k < y.cols(); ++k) f.state.q.segment<3>(3 * (at + k)) = y.col(k);
    at += static_cast<int>(y.cols());
    f.yarn_cp_counts.push_back(static_cast<int>(y.cols()));
    f.yarn_radius.push_back(r);
  }
  if (stitches)
    for (int s = 0; s < f.num_seg(); ++s) f.stitch.push_back({s / 8, s % 8});
  return f;
}

inline StateFile helix_state(double time = 0) {
  return state_of({helix_control_points()}, 0.125, time);
}

/// A fresh empty folder under the system temp directory, named after the test and process.
inline std::filesystem::path temp_dir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("knit-test-" + name + "-" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace knit::test
