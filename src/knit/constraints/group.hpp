#pragma once
// A constraint group: a block of rows C(q, t) = 0 with their gradient ∇C, handed to the
// fast projection (MODEL.md §5.2), which is generic over groups. Each group is one file
// pair: inextensibility (inextensibility.hpp), pins (pin.hpp), glue (glue.hpp), clamps
// (clamp.hpp). A group only says what its rows are; the projection owns the matrices and
// reports, per group, the multipliers and the force and torque the group exerted
// (StepData's ConstraintRecord).
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <string>
#include <string_view>
#include <vector>

namespace knit {

class Model;
struct ConstraintRecord;

class ConstraintGroup {
 public:
  explicit ConstraintGroup(std::string name) : m_name(std::move(name)) {}
  virtual ~ConstraintGroup() = default;
  /// "length", "pin", "glue", "clamp".
  virtual std::string_view kind() const = 0;
  /// Unique within a model: "length", "pin0", "glue1", a clamp's name.
  const std::string& name() const { return m_name; }
  /// Number of scalar rows.
  virtual int rows() const = 0;
  /// Appends the non-zeros of ∇C as (row within the group, dof, value). Duplicate
  /// entries are summed. When jacobian_varies(), only the structure matters: no entry may
  /// repeat, and evaluate() supplies the values.
  virtual void jacobian_structure(const Model& model,
                                  std::vector<Eigen::Triplet<double>>& entries) const = 0;
  /// Whether ∇C depends on q (inextensibility) or is constant (point constraints).
  virtual bool jacobian_varies() const { return false; }
  /// Writes C(q, time) into c[0, rows()). When jacobian_varies() and `jacobian` is not
  /// null, also writes ∇C's values row by row, each row's columns ascending.
  virtual void evaluate(const Model& model, const Eigen::VectorXd& q, double time, double* c,
                        double* jacobian) const = 0;
  /// The point about which the group's torque is reported (cm). Default: the origin.
  virtual Eigen::Vector3d torque_point(const Model& model, const Eigen::VectorXd& q,
                                       double time) const {
    return Eigen::Vector3d::Zero();
  }
  /// Whether the group can exert a net force or torque on the yarns. A group whose C is
  /// invariant under rigid motion (inextensibility) cannot: its force and torque are zero
  /// exactly and are not summed (only its multipliers are reported).
  virtual bool exerts_net_force() const { return true; }
  /// Adjusts the generic report (see ConstraintRecord) where the group means something
  /// more specific; `h` is the step (s).
  virtual void finish_record(ConstraintRecord& record, double h) const {}

 private:
  std::string m_name;
};

}  // namespace knit
