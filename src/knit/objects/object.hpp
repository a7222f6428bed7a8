#pragma once
// A solid object in a scene: a shape (shape.hpp, in the object's own frame) placed at a
// position and rotation, optionally moving rigidly along keyframes, and how the yarn
// collides with it (MODEL.md §3 penalty and §5.3 collision filter; either or both).
//
// Placement at time t: a point x of the object frame is at
//     X(x, t) = p + T(t) + R(t) R₀ x
// with p = position, R₀ = rotation, and T(t), R(t) the keyframes' translation and rotation
// (interpolate_keyframes: linear and slerp, held outside the keyframes), so a keyframed
// object turns about its position. Its velocity at a world point X is
//     u(X, t) = Ṫ + ω × (X − p − T(t)),
// which the penalty's damping and the filter's friction act on (relative velocity).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "knit/model/model.hpp"
#include "knit/model/step_data.hpp"
#include "knit/objects/shape.hpp"

namespace knit {

struct SceneObject {
  std::string name;  ///< unique in its scene; names the object in records and logs
  ShapePtr shape;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();            ///< p (cm)
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();  ///< R₀
  std::vector<Keyframe> keyframes;  ///< rigid motion (by increasing time); empty: static
  /// Penalty (MODEL.md §3): E = k ℓ_i ∫ (φ(y) − r)² over the yarn points with φ < r, and
  /// a normal damping force −c ℓ_i ∫ (n·w) n on them (w = yarn velocity − object velocity).
  bool penalty = false;
  double stiffness = 1e4;  ///< k (g/(cm s²) = erg/cm³): 2k is the spring per yarn length
  double damping = 2;      ///< c (g/(cm s)) of the penalty's normal damping
  /// Collision filter (MODEL.md §5.3): at the velocity-filter stage, sample points within r
  /// of the surface lose their approaching normal velocity (plus a push-out of the
  /// penetration over one step), and Coulomb friction with coefficient `friction` acts on
  /// their tangential velocity.
  bool filter = true;
  double friction = 0.5;  ///< Coulomb coefficient μ (filter; ≥ 0)

  /// True when the object moves (has keyframes).
  bool moving() const { return keyframes.size() > 1; }
};

/// An object's placement and motion frozen at one time, for fast evaluation of many
/// points.
class ObjectFrame {
 public:
  ObjectFrame(const SceneObject& object, double time);
  /// φ at world point x (cm) and its world gradient (when grad is not null).
  double distance(const Eigen::Vector3d& x, Eigen::Vector3d* grad) const {
    const Eigen::Vector3d local = m_to_local * (x - m_origin);
    if (!grad) return m_shape->distance(local, nullptr);
    Eigen::Vector3d g;
    const double phi = m_shape->distance(local, &g);
    *grad = m_to_world * g;
    return phi;
  }
  /// The object's velocity at world point x (cm/s).
  Eigen::Vector3d velocity(const Eigen::Vector3d& x) const {
    return m_velocity + m_omega.cross(x - m_origin);
  }
  /// True when a ball of radius `rho` around x lies wholly where φ > `level`.
  bool ball_outside(const Eigen::Vector3d& x, double rho, double level) const {
    return distance(x, nullptr) > level + m_lipschitz * rho;
  }
  /// World position of object-frame point x.
  Eigen::Vector3d to_world(const Eigen::Vector3d& x) const { return m_origin + m_to_world * x; }
  const Eigen::Vector3d& origin() const { return m_origin; }
  const Eigen::Matrix3d& rotation() const { return m_to_world; }

 private:
  const Shape* m_shape;
  Eigen::Vector3d m_origin;
  Eigen::Matrix3d m_to_world, m_to_local;
  Eigen::Vector3d m_velocity, m_omega;
  double m_lipschitz;
};

/// What one collision mechanism (the penalty term or the collision filter) found against
/// one object: yarn points within r of its surface, the deepest overlap r − φ (cm), and
/// what it exerted on the yarn: a force (dyn) or an impulse (g cm/s).
struct ObjectContacts {
  long long points = 0;
  double deepest = 0;
  Eigen::Vector3d push = Eigen::Vector3d::Zero();
  void add(const ObjectContacts& other) {
    points += other.points;
    deepest = std::max(deepest, other.deepest);
    push += other.push;
  }
};

/// Adds `contacts[k]`, found against model object `objects[k]`, into data.objects, their
/// push times `force_scale` (1 for a force, 1/h for an impulse over a step of h).
void record_contacts(const std::vector<int>& objects, const std::vector<ObjectContacts>& contacts,
                     double force_scale, StepData& data);

/// Centre and radius (cm) of a ball holding segment i's centreline: the centroid of its 4
/// control points and their largest distance from it (the curve lies in the control
/// points' convex hull).
void segment_ball(const Model& model, const Eigen::VectorXd& q, int segment,
                  Eigen::Vector3d& centre, double& radius);

}  // namespace knit
