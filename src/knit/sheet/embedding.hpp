#pragma once
// Barycentric embedding of points (yarn control points) in the sheet, to draw a simulated
// sheet as yarn: each point p, given in the undeformed configuration, is attached to the
// rest triangle nearest to it (closest-point distance), with the barycentric coordinates
// b of its projection onto that triangle's plane and its signed offset h along the
// triangle's unit normal n = (X1 − X0) × (X2 − X0)/‖…‖ (cm):
//   p = Σᵢ bᵢ Xᵢ + h n                    (rest positions Xᵢ; exact up to round-off)
// and is carried along by the deformed sheet as
//   x = Σᵢ bᵢ xᵢ + h n(x)                  (deformed positions xᵢ and unit normal).
// A point beyond the mesh's edge keeps the plane projection's barycentric coordinates
// (some negative: it extrapolates the nearest triangle) so the rest shape still maps it
// back exactly. The nearest triangle is found with a uniform grid of triangle bounds.
#include <Eigen/Core>
#include <vector>

#include "knit/sheet/sheet.hpp"

namespace knit::sheet {

/// Points attached to a sheet's triangles.
struct SheetEmbedding {
  std::vector<int> triangle;  ///< per point, the rest mesh's nearest triangle
  Eigen::Matrix3Xd bary;      ///< per point, barycentric coordinates (b0, b1, b2), Σ = 1
  Eigen::VectorXd offset;     ///< per point, signed normal offset h, cm
  /// Number of embedded points.
  int size() const { return static_cast<int>(triangle.size()); }
};

/// Embeds `points` (cm, one column each, undeformed configuration) in the rest mesh.
/// Runs in parallel over points (TBB); the result does not depend on the thread count
/// (ties between equally near triangles go to the lower index). Throws
/// std::invalid_argument for non-finite points or a mesh without triangles.
SheetEmbedding embed_points(const SheetMesh& mesh, const Eigen::Matrix3Xd& points);

/// The embedded points carried by the sheet at `positions` (cm, 3 per node). Throws
/// std::invalid_argument when positions has the wrong size.
Eigen::Matrix3Xd deform(const SheetMesh& mesh, const SheetEmbedding& embedding,
                        const Eigen::VectorXd& positions);

/// Closest point to p on triangle (a, b, c), cm (Ericson, Real-Time Collision Detection
/// §5.1.5); exposed for tests.
Eigen::Vector3d closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                          const Eigen::Vector3d& b, const Eigen::Vector3d& c);

}  // namespace knit::sheet
