#pragma once
// The crossing check: did any two pieces of yarn pass through each other between two
// states? Independent of the contact energy (it shares only the BVH): a test of what the
// contact is meant to prevent, for the tests, for runs (`--check-crossings`) and for the
// summaries.
//
// Method. Each spline segment is followed at P + 1 parameters u = k/P (P =
// samples_per_segment): the polyline through those points. A B-spline point is linear in
// the control points, so when the control points move linearly from q0 to q1 (s ∈ [0, 1])
// every polyline vertex moves linearly too, and the polyline's motion is exact. Two moving
// edges pass through each other at an s where their four end points become coplanar —
// a root of the cubic det[a1 − a0, b0 − a0, b1 − a0](s) at which its sign changes — and the
// two edges meet there (the closest points of their lines lie within both). A root at
// which the sign does not change is a touch (the edges come together and part on the
// side they came from): not a crossing. Each pair of segments is reported once per
// step, at its first crossing.
//
// What it can miss: a crossing of the yarns (the splines) that their polylines do not make
// — only when the two yarns come within the polylines' sag (≈ κ (1/P)² ℓ² / 8 for a
// segment of length ℓ and curvature κ: about 0.01 cm for knitsim's stitches, against a yarn
// diameter of 0.25 cm) — and crossings of a segment with itself or with its neighbour on
// the same yarn (they share a point, as in the contact energy). Pairs the model keeps out
// of contact (Model::contact_exclusions: the yarn around a glued point) are not checked:
// a glue is allowed to pull its ends through.
//
// Cost: one BVH over the segments' swept boxes and P² edge tests per pair of boxes that
// overlap; linear in the yarn for a step that moves each point by less than a stitch.
#include <Eigen/Core>
#include <vector>

namespace knit {

class Model;

/// Two pieces of yarn passing through each other within a step.
struct SegmentCrossing {
  int segment_a = -1, segment_b = -1;  ///< global segment indices, a < b
  double step_fraction = 0;            ///< s ∈ [0, 1]: when in the step (q0 + s (q1 − q0))
  double u_a = 0, u_b = 0;             ///< where on each segment (spline parameter)
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  ///< where (cm), at that moment
};

/// A straight edge whose end points move linearly over a step: p at the start, p + d·s.
struct MovingEdge {
  Eigen::Vector3d p0, p1;  ///< ends at s = 0
  Eigen::Vector3d d0, d1;  ///< their displacements over the step (the ends at s = 1 minus p)
};

/// One edge passing through another.
struct EdgeCrossing {
  double s = 0;  ///< when (fraction of the step)
  double u = 0;  ///< where on the first edge (0 at p0, 1 at p1)
  double v = 0;  ///< where on the second
};

/// Every moment within the step (0, 1] at which edge `a` passes through edge `b`, in order.
/// Parallel edges (which only cross by sliding along each other in their plane) and edges
/// that stay coplanar throughout the step are never reported.
std::vector<EdgeCrossing> edge_crossings(const MovingEdge& a, const MovingEdge& b);

/// Default polyline points per segment (P) of find_crossings.
inline constexpr int CROSSING_SAMPLES_PER_SEGMENT = 4;

/// The pairs of segments of `model` that passed through each other while the control
/// points moved linearly from q0 to q1 (each of length model.num_dof()), ordered by
/// (segment_a, segment_b). Throws std::invalid_argument for vectors of the wrong size or
/// samples_per_segment outside [1, 64].
std::vector<SegmentCrossing> find_crossings(const Model& model, const Eigen::VectorXd& q0,
                                            const Eigen::VectorXd& q1,
                                            int samples_per_segment = CROSSING_SAMPLES_PER_SEGMENT);

}  // namespace knit
