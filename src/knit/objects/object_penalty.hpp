#pragma once
// The object penalty term (MODEL.md §3 "Objects with implicit surfaces"), with a normal
// damping like the yarn–yarn contact damping, for every object of the model whose
// `penalty` is on. Per segment i (rest length ℓ_i), over the energy quadrature
// (Simpson: points t_q, weights w_q) and the yarn points y = y_i(t_q) with φ(y) < r:
//
//     E_i = k ℓ_i Σ_q w_q (φ(y) − r)²                                  (erg)
//     F_a = −Σ_q w_q ℓ_i B_a(t_q) [ 2k (φ(y) − r) ∇φ(y) + c (n·w) n ]   (dyn)
//
// with φ and ∇φ the object's distance at the evaluation's time, n = ∇φ/|∇φ|, and
// w = ẏ − u the yarn's velocity relative to the object's (ObjectFrame::velocity). The
// elastic part is exactly −∂E/∂q; the damping part is −∂D/∂q̇ of
// D = ½ c ℓ_i Σ_q w_q (n·w)². Units: k in g/(cm s²) (erg/cm³: 2k is a spring per cm of
// yarn), c in g/(cm s). The tube (radius r) just touches the surface at φ = r, where the
// energy and its gradient vanish.
//
// A segment whose control points' ball lies wholly where φ > r (ObjectFrame::ball_outside)
// is skipped after one evaluation of φ.
#include <string>
#include <vector>

#include "knit/energy/segment_accumulator.hpp"
#include "knit/energy/term.hpp"
#include "knit/objects/object.hpp"

namespace knit {

class ObjectPenalty : public Term {
 public:
  /// The term for the model's objects with `penalty` on (none: it does nothing).
  explicit ObjectPenalty(const Model& model);
  std::string_view name() const override { return "objects"; }
  double add_force(const Model& model, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                   double time, Eigen::VectorXd& force) override;
  /// Adds, per penalty object, the points in contact, the deepest penetration and the
  /// force on the yarn at the last evaluation into data.objects.
  void record(StepData& data) const override;
  /// Objects this term acts on (indices into model.objects).
  const std::vector<int>& objects() const { return m_objects; }

 private:
  std::vector<int> m_objects;
  SegmentAccumulator m_acc;
  std::vector<ObjectContacts> m_last;  // per entry of m_objects; push = force (dyn)
  std::vector<std::vector<ObjectContacts>> m_seg_stats;  // scratch: per object, per segment
};

}  // namespace knit
