#pragma once
// Velocity filters (MODEL.md §5.3) change control-point velocities directly after the
// constrained step: non-rigid (rigid-region) damping and distance-field collisions.
#include <Eigen/Core>
#include <string_view>

#include "knit/model/model.hpp"

namespace knit {

class VelocityFilter {
 public:
  virtual ~VelocityFilter() = default;
  /// Short stable name used in timings ("nonrigid_damping", "plane", …).
  virtual std::string_view name() const = 0;
  /// Changes the control-point velocities `v` (cm/s) of positions `q` (cm) at `time` (s),
  /// the end of a step of length `h` (s; a filter that removes a penetration over the next
  /// step needs it). Every impulse of one filter is computed from the same velocities,
  /// then applied.
  virtual void apply(const Model& model, const Eigen::VectorXd& q, Eigen::VectorXd& v, double time,
                     double h) = 0;
};

}  // namespace knit
