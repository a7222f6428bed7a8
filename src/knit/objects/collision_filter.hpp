#pragma once
// The collision and friction filter against solid objects (MODEL.md §5.3), for every
// object of the model whose `filter` is on. After the constrained step, at every sample
// point s (SampleSegments: 8 per segment) with φ(x_s) < r, with n = ∇φ/|∇φ|, the
// object's velocity u there and the relative velocity w = v_s − u split as
// w = w_n n + w_t:
//   - normal: the target normal velocity is the push-out rate p = min(r − φ, r/4) / h
//     (the penetration of the tube removed over the next step, at most r/4 of it per
//     step); when w_n < p the normal change is Δw_n = p − w_n, else nothing;
//   - friction (Coulomb, Bridson et al. 2002): Δw_t = −min(1, μ Δw_n / |w_t|) w_t — the
//     sample sticks when the normal change is large enough, and slides slower otherwise.
// Every Δv of one pass is computed from the same velocities and applied as control-point
// impulses J_k = Σ_s m_s B_k(t_s) Δv_s. A lone sample's change spreads over its four
// control points, so it gets only part of what it asked for: the pass is repeated (up to
// PASSES times, on the segments still in contact) until no sample approaches.
//
// The explicit midpoint step moved the positions by h (v + ½ h a) before the filter ran,
// so a sample that friction stops would still creep by ½ h² a per step (a yarn on an
// incline below the friction angle would slide at ½ g sin θ h). As in Bridson et al.
// 2002, where positions follow the corrected velocity, the filter moves the control
// points by ½ h Δv_t of the friction part of its change (adjust_positions): a stuck sample
// then stays where it is. (The normal part needs no such move: the push-out removes the
// penetration over the next step.)
//
// Segments whose control points' ball lies wholly where φ > r are skipped after one
// evaluation of φ per object.
#include <vector>

#include "knit/filters/sample_segments.hpp"
#include "knit/filters/velocity_filter.hpp"
#include "knit/objects/object.hpp"

namespace knit {

class CollisionFilter : public VelocityFilter {
 public:
  static constexpr int PASSES = 4;
  /// The filter for the model's objects with `filter` on (none: it does nothing).
  explicit CollisionFilter(const Model& model, int samples_per_segment = 8);
  std::string_view name() const override { return "collisions"; }
  void apply(const Model& model, const Eigen::VectorXd& q, Eigen::VectorXd& v, double time,
             double h) override;
  /// Adds, per filter object, the samples in contact, the deepest penetration (at the
  /// step's positions) and the impulse / h into data.objects.
  void record(StepData& data) const override;
  /// q += ½ h Δv_t for the friction part Δv_t of the last apply's change (see above).
  bool adjust_positions(const Model& model, Eigen::VectorXd& q) const override;
  const std::vector<int>& objects() const { return m_objects; }

 private:
  std::vector<int> m_objects;
  SampleSegments m_samples;
  std::vector<ObjectContacts> m_last;  // per entry of m_objects; push = impulse (g cm/s)
  double m_h = 0;
  // scratch
  std::vector<char> m_is_near;  // scratch, per segment
  std::vector<int> m_near;      // segments near some filter object
  // a sample point within r of an object's surface
  struct Hit {
    int sample = 0;  // global sample index
    int object = 0;  // index into m_objects
    int near = 0;    // index into m_near of its segment
    Eigen::Vector3d x, n;
    double depth = 0;  // r − φ (cm)
    double push = 0;   // target normal velocity (cm/s)
  };
  std::vector<std::vector<Hit>> m_blocks;  // hits per block of near segments
  Eigen::Matrix3Xd m_dv;
  Eigen::Matrix3Xd m_dvt;    // the friction part of the samples' Δv
  Eigen::VectorXd m_dvt_cp;  // and on the control points
  bool m_changed = false;
  std::vector<int> m_changed_segments, m_touched;  // segments changed by a pass, by the first
};

}  // namespace knit
