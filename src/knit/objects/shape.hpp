#pragma once
// Solid shapes given by a signed distance φ (cm, MODEL.md §3 "Objects with implicit
// surfaces"): φ < 0 inside, φ = 0 on the surface, φ > 0 outside, with its gradient ∇φ
// (unit length where φ is an exact distance). Every shape is described in its object's own
// frame (see SceneObject for where the object is at a time).
//
//   plane      the half-space below a plane through `point` with unit `normal`:
//              φ = n·(x − p) (exact)
//   sphere     φ = |x − c| − R (exact)
//   box        centre c, half extents e (axis-aligned in the object frame; exact)
//   capsule    the points within R of the segment ab (exact)
//   cylinder   a solid cylinder of radius R from a to b, flat caps (exact)
//   ellipsoid  centre c, semi-axes a (axis-aligned): φ ≈ k₀(k₀ − 1)/k₁ with
//              k₀ = |(x − c)/a|, k₁ = |(x − c)/a²| — exact on the surface and for a sphere,
//              within a few % of the distance near the surface of a moderately elongated
//              one (its zero set is exactly the ellipsoid)
//   union      min of the members' φ (exact outside)
//   smooth union  the polynomial smooth minimum of the members with blend radius k (cm):
//              h = clamp(½ + ½(b − a)/k, 0, 1), φ = h a + (1 − h) b − k h (1 − h), whose
//              gradient is exactly h ∇a + (1 − h) ∇b; it fills the creases between members
//              (e.g. a foot's heel and ankle) with a fillet of about k
//   mesh       a closed triangle mesh as a narrow-band signed distance grid (mesh_shape.hpp)
//
// Every φ here changes at most L·|x − y| between two points (L = lipschitz(): 1 for the
// exact distances and their unions, a bound from the axis ratio for the ellipsoid): a ball
// of radius ρ around x lies wholly outside when φ(x) > L ρ, which the object terms use to
// skip far segments with one evaluation.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace knit {

class Shape {
 public:
  virtual ~Shape() = default;
  /// "plane", "sphere", "box", "capsule", "cylinder", "ellipsoid", "union", "smooth_union",
  /// "mesh".
  virtual std::string_view kind() const = 0;
  /// φ(x) (cm) in the object frame; writes ∇φ(x) into *grad when grad is not null.
  virtual double distance(const Eigen::Vector3d& x, Eigen::Vector3d* grad) const = 0;
  /// A box holding the solid (object frame); unbounded shapes (a plane) return a box with
  /// infinite extents.
  virtual Eigen::AlignedBox3d bounds() const = 0;
  /// L with |φ(x) − φ(y)| ≤ L |x − y| everywhere.
  virtual double lipschitz() const { return 1; }
};

using ShapePtr = std::shared_ptr<const Shape>;

ShapePtr make_plane(const Eigen::Vector3d& point, const Eigen::Vector3d& normal);
ShapePtr make_sphere(const Eigen::Vector3d& centre, double radius);
ShapePtr make_box(const Eigen::Vector3d& centre, const Eigen::Vector3d& half_extents);
ShapePtr make_capsule(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius);
ShapePtr make_cylinder(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius);
ShapePtr make_ellipsoid(const Eigen::Vector3d& centre, const Eigen::Vector3d& semi_axes);
/// Union of ≥ 1 members; `blend` > 0 makes it the smooth union with that blend radius (cm).
ShapePtr make_union(std::vector<ShapePtr> members, double blend = 0);

/// The polynomial smooth minimum of a and b with blend radius k > 0 and its weight h on a
/// (the gradient of the result is h ∇a + (1 − h) ∇b).
double smooth_min(double a, double b, double k, double& h);

}  // namespace knit
