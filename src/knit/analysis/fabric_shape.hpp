#pragma once
// Measures of a knitted sample's shape, computed from the yarn and the stitch
// coordinates of its segments (MODEL.md §6: stockinette curls, rib draws in across,
// garter draws in along the wale).
//
// Frame: stitch centroids of the central half of the sample (rows and columns between
// the quartiles) define a best-fit plane; the course axis is the mean direction from
// column to column along the rows, the wale axis the mean direction from row to row, both
// projected into that plane; the normal is course × wale (the fabric's front).
#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "knit/model/model.hpp"

namespace knit {

/// Columns (rows) between the stitch centres the gauge is measured over.
inline constexpr int GAUGE_SPAN = 4;

struct FabricShape {
  int rows = 0, cols = 0;
  double course_extent_cm = 0;  ///< extent of the yarn along the course axis (width)
  double wale_extent_cm = 0;    ///< extent along the wale axis (height)
  double thickness_cm = 0;      ///< extent along the normal over the central half, + 2r
  /// The gauge on the central half: mean distance between stitch centres GAUGE_SPAN
  /// columns apart, per stitch. The span holds a whole 2×2 rib repeat, so a rib that
  /// pleats measures drawn in, and is short enough to follow a sheet that rolls.
  double stitch_width_cm = 0;
  double row_height_cm = 0;  ///< the same along the wale (rows GAUGE_SPAN apart)
  /// Width measured along the fabric through stitch centres GAUGE_SPAN columns apart (a
  /// tape measure laid over rolled edges, not into pleats), mean of the central rows,
  /// plus one stitch width for the half stitches at either end.
  double course_length_cm = 0;
  double wale_length_cm = 0;  ///< the same along the wale, central columns
  double loop_length_cm = 0;  ///< rest yarn length per stitch
  /// Signed mean offset (cm) of each edge's stitch centroids from the central plane,
  /// positive toward the front: left (column 0), right, bottom (row 0), top.
  double edge_offset_cm[4] = {0, 0, 0, 0};
  /// Mean |edge offset| over the four edges divided by the stitch width: 0 for a flat
  /// sheet; about 1 when the edges have rolled one stitch width out of the plane.
  double edge_curl = 0;
  Eigen::Vector3d course_axis, wale_axis, normal;
};

/// Measures the sample; throws if the model has no stitch coordinates or fewer than 2
/// rows or columns.
FabricShape measure_fabric(const Model& model, const Eigen::VectorXd& q);

nlohmann::json to_json(const FabricShape& shape);

}  // namespace knit
