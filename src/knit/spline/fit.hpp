#pragma once
// Least-squares fitting of uniform cubic B-splines to sampled curves (MODEL.md §6: the
// knit generator fits each stitch while continuing from the control points already laid;
// importers fit polylines).
#include <Eigen/Core>

namespace knit {

/// Fits a uniform cubic B-spline with `segments` segments (segments + 3 control points)
/// to `samples` (3×n) at global parameters `u` ∈ [0, segments] (segment i covers
/// [i, i+1]). The first `fixed.cols()` control points are held at `fixed` (continuation
/// of an existing spline). A small second-difference penalty `smoothing` (relative to the
/// data term) keeps the system well posed when samples are sparse. Returns 3×(segments+3).
Eigen::Matrix3Xd fit_bspline(const Eigen::Matrix3Xd& samples, const Eigen::VectorXd& u,
                             int segments, const Eigen::Matrix3Xd& fixed = Eigen::Matrix3Xd(),
                             double smoothing = 1e-6);

/// Fits a polyline with chord-length parameterisation. `segments` ≥ 1.
Eigen::Matrix3Xd fit_polyline(const Eigen::Matrix3Xd& polyline, int segments);

/// Length of a polyline (cm).
double polyline_length(const Eigen::Matrix3Xd& polyline);

/// Samples a B-spline with control points `cp` (3×m) at `per_segment` points per
/// segment (plus the final end point). Returns 3×((m−3)·per_segment + 1).
Eigen::Matrix3Xd sample_bspline(const Eigen::Matrix3Xd& cp, int per_segment);

}  // namespace knit
