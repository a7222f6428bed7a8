#pragma once
// A physical term of the equations of motion M q̈ = −∇E − ∇_q̇ D + f_ext (MODEL.md §2).
#include <Eigen/Core>
#include <string_view>

#include "knit/model/model.hpp"

namespace knit {

class Term {
 public:
  virtual ~Term() = default;
  /// Short stable name ("bending", "contact", …) used in timings and logs.
  virtual std::string_view name() const = 0;
  /// Adds the term's generalised force −∂E/∂q − ∂D/∂q̇ (dyn, per coordinate) into `force`
  /// and returns its potential energy E (erg = g cm²/s²; 0 for pure damping).
  virtual double add_force(const Model& model, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                           Eigen::VectorXd& force) = 0;
  /// Potential energy alone (erg).
  virtual double energy(const Model& model, const Eigen::VectorXd& q) {
    Eigen::VectorXd f = Eigen::VectorXd::Zero(q.size());
    return add_force(model, q, Eigen::VectorXd::Zero(q.size()), f);
  }
};

}  // namespace knit
