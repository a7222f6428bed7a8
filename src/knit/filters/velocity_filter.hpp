#pragma once
// Velocity filters (MODEL.md §5.3) change control-point velocities directly after the
// constrained step: non-rigid (rigid-region) damping and distance-field collisions.
#include <Eigen/Core>
#include <string_view>

#include "knit/model/model.hpp"
#include "knit/model/step_data.hpp"

namespace knit {

class VelocityFilter {
 public:
  virtual ~VelocityFilter() = default;
  /// Short stable name used in timings ("nonrigid_damping", "collisions").
  virtual std::string_view name() const = 0;
  /// Called by the simulator before each apply with the state the step started from: its
  /// positions and its records (StepData's force records: the contact set with its normal
  /// forces, the objects). A filter that acts on what the forces found or on how far the
  /// step moved keeps what it needs (yarn–yarn friction: the contact pairs and where they
  /// were); the default ignores them.
  virtual void begin_step(const StepData& start, const Eigen::VectorXd& q_start) {}
  /// Changes the control-point velocities `v` (cm/s) of positions `q` (cm) at `time` (s),
  /// the end of a step of length `h` (s; a filter that removes a penetration over the next
  /// step needs it). Every impulse of one filter is computed from the same velocities,
  /// then applied.
  virtual void apply(const Model& model, const Eigen::VectorXd& q, Eigen::VectorXd& v, double time,
                     double h) = 0;
  /// Moves positions `q` for the velocity change the last apply made, when the step's
  /// position update should have seen it; returns whether it moved any. The collision
  /// filter does (see collision_filter.hpp); the default moves nothing.
  virtual bool adjust_positions(const Model& model, Eigen::VectorXd& q) const { return false; }
  /// The step whose apply this filter last ran was thrown away (it failed after the
  /// filters: a yarn torn apart, a value not finite) and will be taken again from where it
  /// started: a filter that keeps something from one step to the next puts it back as it
  /// was before that apply. The default keeps nothing.
  virtual void reject_step() {}
  /// Writes what the last apply found and did into the step data (the collision filter:
  /// contacts, penetration, impulse). Called by the simulator after the step's forward at
  /// its result.
  virtual void record(StepData& data) const {}
};

}  // namespace knit
