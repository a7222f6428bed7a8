#pragma once
// Non-rigid motion damping (MODEL.md §4), a velocity filter standing in for yarn "fuzz":
// fixed, overlapping regions of the cloth are nudged toward their own rigid motion.
//
// For each region R (a set of segments, hence of their sample segments) with weights
// w_s = m_s / r(s) — a sample's mass shared among the r(s) regions of the pass containing
// it — compute the centre of mass x_c, linear momentum P, angular momentum L about x_c and
// inertia tensor I, hence v_rigid(x) = P / M + ω × (x − x_c), ω = I⁺ L (pseudo-inverse: a
// region whose samples are collinear gets no spin about their line). Then
//     Δv(s) = (α / r(s)) Σ_{R ∋ s} (v_rigid,R(s) − v(s)).
// Because every region's fit uses the shared weights, Σ_s m_s Δv_s = 0 and
// Σ_s m_s x_s × Δv_s = 0: the pass conserves the cloth's linear and angular momentum
// exactly (also at the control points, see SampleSegments), whatever α and the overlaps.
//
// Regions from stitch coordinates (Model::stitch; segments with row −1 are never touched):
//  - small, one per stitch (r, c): the loop of (r, c) with the loop it is pulled through,
//    (r − 1, c) (just (0, c) on row 0). Each loop is in two of them, so they overlap along
//    the wale; side by side they are joined by the yarn itself and by the large regions.
//    Strength α_small.
//  - large: blocks of 4 × 4 stitches starting every 2 rows and 2 columns (from −2, clipped
//    to the fabric; around a tube they wrap past the seam), so that every stitch lies in
//    2 × 2 of them. Strength α_large.
// The small pass runs first, then the large one on the velocities it left.
#include <Eigen/Core>
#include <string_view>
#include <vector>

#include "knit/filters/sample_segments.hpp"
#include "knit/filters/velocity_filter.hpp"

namespace knit {

/// Lists of segment indices, one per region.
using RegionList = std::vector<std::vector<int>>;

/// One small region per stitch: segments of (r, c) and (r − 1, c).
RegionList small_stitch_regions(const Model& model);
/// Blocks of `block` × `block` stitches starting every `stride` rows and columns. With
/// `wrap_columns` (a tube knitted in the round) the blocks run on around the seam from
/// the last column into the first, so the seam is damped like any other column.
RegionList large_stitch_regions(const Model& model, int block = 4, int stride = 2,
                                bool wrap_columns = false);

/// The time step the damping strengths α are given for: MODEL.md §8's h = 1/11800 s. The
/// filter damps the same per unit of time at any step: at step h a pass removes the
/// fraction 1 − (1 − α)^(h / FILTER_REFERENCE_STEP) of the non-rigid velocity (exactly α
/// at the reference step; two steps of h/2 remove what one of h does).
constexpr double FILTER_REFERENCE_STEP = 1.0 / 11800;
/// That per-step strength for α at step h (s); α itself when h is not positive.
double per_step_strength(double alpha, double h);

/// One pass: the regions, their strength α ∈ [0, 1] and the segment → regions map.
class RigidRegionPass {
 public:
  RigidRegionPass(const Model& model, RegionList regions, double alpha);
  /// Adds this pass's Δv for every sample (3 × num_samples) from sample positions x and
  /// velocities u, at strength `strength` (α of the reference step when negative).
  void velocity_change(const SampleSegments& samples, const Eigen::Matrix3Xd& x,
                       const Eigen::Matrix3Xd& u, Eigen::Matrix3Xd& dv, double strength = -1) const;
  double alpha() const { return m_alpha; }
  const RegionList& regions() const { return m_regions; }

 private:
  RegionList m_regions;
  double m_alpha;
  std::vector<int> m_seg_begin;  // CSR: regions containing each segment
  std::vector<int> m_seg_regions;
  // per-evaluation scratch (reused: no allocation in the steady state)
  struct Moments {
    double m = 0;
    Eigen::Vector3d mx, mu, xu;  // Σw x, Σw u, Σw x×u
    Eigen::Matrix3d xx;          // Σw x xᵀ
  };
  struct RigidFit {
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
    Eigen::Vector3d omega = Eigen::Vector3d::Zero();
  };
  mutable std::vector<Moments> m_moments;
  mutable std::vector<RigidFit> m_fit;
};

class NonRigidDampingFilter : public VelocityFilter {
 public:
  /// The two passes of MODEL.md §4 from the model's stitch coordinates; `wrap_columns`
  /// for a tube (see large_stitch_regions).
  NonRigidDampingFilter(const Model& model, double alpha_small, double alpha_large,
                        bool wrap_columns = false, int samples_per_segment = 8);
  /// A single pass over explicit regions (lists of segment indices).
  NonRigidDampingFilter(const Model& model, RegionList regions, double alpha,
                        int samples_per_segment = 8);

  std::string_view name() const override { return "nonrigid_damping"; }
  void apply(const Model& model, const Eigen::VectorXd& q, Eigen::VectorXd& v, double time,
             double h) override;

  const SampleSegments& samples() const { return m_samples; }
  const std::vector<RigidRegionPass>& passes() const { return m_passes; }

 private:
  SampleSegments m_samples;
  std::vector<RigidRegionPass> m_passes;
  Eigen::Matrix3Xd m_x, m_u, m_dv;  // sample positions, velocities, velocity changes
};

}  // namespace knit
