// The barycentric embedding of yarn points in the sheet (src/knit/sheet/embedding.hpp):
// exact reproduction by the rest mesh, rigid motions, normal offsets, the grid search
// against brute force, and the speed the paper's swatches need.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <limits>
#include <random>
#include <stdexcept>

#include "knit/sheet/embedding.hpp"
#include "knit/sheet/sheet.hpp"

namespace knit::sheet {
namespace {

// a mesh that is not a flat grid: a rectangle draped over a cylinder of radius 6 cm
SheetMesh curved_mesh() {
  SheetMesh flat = make_rectangle(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(),
                                  Eigen::Vector3d::UnitY(), 8.0, 5.0, 9, 6);
  Eigen::Matrix3Xd rest = flat.rest;
  for (int i = 0; i < rest.cols(); ++i) {
    const double a = rest(0, i) / 6.0;
    rest.col(i) = Eigen::Vector3d(6 * std::sin(a), rest(1, i), 6 * (std::cos(a) - 1));
  }
  return make_sheet_mesh(rest, flat.uv, flat.triangles);
}

SheetMesh flat_mesh() {
  return make_rectangle(Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(1, 1, 0),
                        Eigen::Vector3d(-1, 1, 0.5), 6.0, 4.0, 7, 5);
}

// random points around the mesh's bounding box, some beyond its edges, off its surface
Eigen::Matrix3Xd random_points(const SheetMesh& mesh, int n, double margin, unsigned seed) {
  std::mt19937 rng(seed);
  const Eigen::Vector3d lo = mesh.rest.rowwise().minCoeff().array() - margin;
  const Eigen::Vector3d hi = mesh.rest.rowwise().maxCoeff().array() + margin;
  std::uniform_real_distribution<double> u(0, 1);
  Eigen::Matrix3Xd p(3, n);
  for (int k = 0; k < n; ++k)
    for (int a = 0; a < 3; ++a) p(a, k) = lo[a] + (hi[a] - lo[a]) * u(rng);
  return p;
}

TEST(SheetEmbedding, RestMeshReproducesThePoints) {
  for (const SheetMesh& mesh : {flat_mesh(), curved_mesh()}) {
    const Eigen::Matrix3Xd p = random_points(mesh, 2000, 0.5, 1);
    const SheetEmbedding e = embed_points(mesh, p);
    ASSERT_EQ(e.size(), 2000);
    const Eigen::Matrix3Xd q = deform(mesh, e, mesh.rest_positions());
    EXPECT_LT((q - p).cwiseAbs().maxCoeff(), 1e-12);
    for (int k = 0; k < e.size(); ++k) EXPECT_NEAR(e.bary.col(k).sum(), 1.0, 1e-12);
  }
}

TEST(SheetEmbedding, RigidMotionMovesThePointsRigidly) {
  const SheetMesh mesh = curved_mesh();
  const Eigen::Matrix3Xd p = random_points(mesh, 1000, 0.3, 2);
  const SheetEmbedding e = embed_points(mesh, p);
  const Eigen::Matrix3d rot =
      Eigen::AngleAxisd(2.1, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  const Eigen::Vector3d shift(3, -4, 12);
  const Eigen::Matrix3Xd moved_rest = (rot * mesh.rest).colwise() + shift;
  const Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXd>(moved_rest.data(), moved_rest.size());
  const Eigen::Matrix3Xd q = deform(mesh, e, x);
  const Eigen::Matrix3Xd expected = (rot * p).colwise() + shift;
  EXPECT_LT((q - expected).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(SheetEmbedding, PointsOffTheSheetKeepTheirNormalOffset) {
  // a flat sheet in z = 0, stretched in its plane: a point at height h stays at height h
  const SheetMesh mesh = make_rectangle(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(),
                                        Eigen::Vector3d::UnitY(), 5.0, 3.0, 6, 4);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 1);
  Eigen::Matrix3Xd p(3, 500);
  for (int k = 0; k < p.cols(); ++k)
    p.col(k) = Eigen::Vector3d(5 * u(rng), 3 * u(rng), 0.4 * (u(rng) - 0.5));
  const SheetEmbedding e = embed_points(mesh, p);
  // the normals of make_rectangle's triangles are û × v̂ = +z
  for (int k = 0; k < p.cols(); ++k) EXPECT_NEAR(e.offset[k], p(2, k), 1e-14);
  Eigen::Matrix3Xd stretched = mesh.rest;
  stretched.row(0) *= 1.3;
  stretched.row(1) *= 0.8;
  const Eigen::Matrix3Xd q =
      deform(mesh, e, Eigen::Map<const Eigen::VectorXd>(stretched.data(), stretched.size()));
  for (int k = 0; k < p.cols(); ++k) {
    EXPECT_NEAR(q(2, k), p(2, k), 1e-12);
    EXPECT_NEAR(q(0, k), 1.3 * p(0, k), 1e-12);
    EXPECT_NEAR(q(1, k), 0.8 * p(1, k), 1e-12);
  }
}

TEST(SheetEmbedding, GridSearchFindsTheNearestTriangle) {
  // oracle: brute force over all triangles
  for (const SheetMesh& mesh : {flat_mesh(), curved_mesh()}) {
    const Eigen::Matrix3Xd p = random_points(mesh, 3000, 2.0, 4);
    const SheetEmbedding e = embed_points(mesh, p);
    auto dist = [&](int t, const Eigen::Vector3d& q) {
      const auto& tri = mesh.triangles[t];
      return (closest_point_on_triangle(q, mesh.rest.col(tri[0]), mesh.rest.col(tri[1]),
                                        mesh.rest.col(tri[2])) -
              q)
          .norm();
    };
    for (int k = 0; k < p.cols(); ++k) {
      double best = std::numeric_limits<double>::infinity();
      for (int t = 0; t < static_cast<int>(mesh.triangles.size()); ++t)
        best = std::min(best, dist(t, p.col(k)));
      EXPECT_NEAR(dist(e.triangle[k], p.col(k)), best, 1e-12) << "point " << k;
    }
  }
}

TEST(SheetEmbedding, ClosestPointOnTriangleMatchesSampling) {
  const Eigen::Vector3d a(0, 0, 0), b(2, 0.2, 0.1), c(0.3, 1.5, -0.2);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-2, 3);
  for (int k = 0; k < 200; ++k) {
    const Eigen::Vector3d p(u(rng), u(rng), u(rng));
    const double d = (closest_point_on_triangle(p, a, b, c) - p).norm();
    double best = std::numeric_limits<double>::infinity();
    for (int i = 0; i <= 100; ++i)
      for (int j = 0; i + j <= 100; ++j)
        best = std::min(best, (a + (b - a) * (i / 100.0) + (c - a) * (j / 100.0) - p).norm());
    EXPECT_LE(d, best + 1e-12);
    EXPECT_GE(d, best - 0.03);
  }
}

TEST(SheetEmbedding, ALargeSwatchMapsBackExactly) {
  // a sheet of the paper's size, 20k triangles (101 × 101 nodes), with 30k points: the
  // grid search finds a triangle for every point and the rest mesh maps them back
  const SheetMesh mesh = make_rectangle(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(),
                                        Eigen::Vector3d::UnitY(), 30.0, 30.0, 101, 101);
  ASSERT_EQ(mesh.triangles.size(), 20000u);
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> u(0, 1);
  Eigen::Matrix3Xd p(3, 30000);
  for (int k = 0; k < p.cols(); ++k)
    p.col(k) = Eigen::Vector3d(30 * u(rng), 30 * u(rng), 0.1 * (u(rng) - 0.5));
  const SheetEmbedding e = embed_points(mesh, p);
  const Eigen::Matrix3Xd q = deform(mesh, e, mesh.rest_positions());
  EXPECT_LT((q - p).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(SheetEmbedding, BadInputThrows) {
  const SheetMesh mesh = flat_mesh();
  Eigen::Matrix3Xd p = Eigen::Matrix3Xd::Zero(3, 2);
  p(0, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(embed_points(mesh, p), std::invalid_argument);
  const SheetEmbedding e = embed_points(mesh, Eigen::Matrix3Xd::Zero(3, 2));
  EXPECT_THROW(deform(mesh, e, Eigen::VectorXd::Zero(7)), std::invalid_argument);
}

}  // namespace
}  // namespace knit::sheet
