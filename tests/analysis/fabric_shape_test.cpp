#include "knit/analysis/fabric_shape.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <functional>

namespace knit {
namespace {

// A synthetic "fabric": one straight yarn per row along x, 2 segments per stitch, rows
// stacked along y. `warp` maps each control point (to bend or rotate the sheet).
Model grid(int rows, int cols, double w, double h, Eigen::VectorXd& q,
           const std::function<Eigen::Vector3d(Eigen::Vector3d)>& warp) {
  ModelBuilder b;
  std::vector<StitchCoord> st;
  for (int r = 0; r < rows; ++r) {
    const int segs = 2 * cols;
    Eigen::Matrix3Xd cp(3, segs + 3);
    for (int k = 0; k < segs + 3; ++k) cp.col(k) = warp(Eigen::Vector3d((k - 1) * w / 2, r * h, 0));
    b.add_yarn(cp);
    for (int i = 0; i < segs; ++i) st.push_back({r, i / 2});
  }
  b.set_stitches(st);
  q = b.positions();
  return b.build(Params{});
}

TEST(FabricShape, FlatSheetHasKnownSpacingAndNoCurl) {
  Eigen::VectorXd q;
  const Model m = grid(12, 10, 0.5, 0.4, q, [](Eigen::Vector3d p) { return p; });
  const FabricShape s = measure_fabric(m, q);
  EXPECT_EQ(s.rows, 12);
  EXPECT_EQ(s.cols, 10);
  EXPECT_NEAR(s.stitch_width_cm, 0.5, 1e-9);
  EXPECT_NEAR(s.row_height_cm, 0.4, 1e-9);
  EXPECT_NEAR(s.course_extent_cm, 10 * 0.5, 1e-9);
  EXPECT_NEAR(s.wale_extent_cm, 11 * 0.4, 1e-6);
  EXPECT_NEAR(s.course_length_cm, 10 * 0.5, 1e-9);
  EXPECT_NEAR(s.wale_length_cm, 12 * 0.4, 1e-9);
  EXPECT_NEAR(s.thickness_cm, 2 * m.params.material.radius, 1e-9);
  EXPECT_NEAR(s.edge_curl, 0.0, 1e-9);
}

// An accordion folded at every column boundary (as a 1×1 rib draws in): the yarn path per
// stitch keeps its length w, but the gauge, measured along the course on the fabric laid
// flat, is w cos θ.
TEST(FabricShape, PleatedSheetMeasuresItsProjectedGauge) {
  const double w = 0.5, theta = 0.6;
  Eigen::VectorXd q;
  const Model m = grid(10, 12, w, 0.4, q, [&](Eigen::Vector3d p) {
    const double u = p.x() / w, tri = std::abs(u - 2 * std::floor(0.5 * u + 0.5));  // 0…1
    return Eigen::Vector3d(p.x() * std::cos(theta), p.y(), tri * w * std::sin(theta));
  });
  const FabricShape s = measure_fabric(m, q);
  EXPECT_NEAR(s.stitch_width_cm, w * std::cos(theta), 1e-9);
  EXPECT_NEAR(s.row_height_cm, 0.4, 1e-9);
  EXPECT_NEAR(s.course_length_cm, 12 * w * std::cos(theta), 0.05 * w);
  EXPECT_GT(s.thickness_cm, 2 * m.params.material.radius + 0.5 * w * std::sin(theta));
}

TEST(FabricShape, MeasuresAreRotationInvariant) {
  const Eigen::Matrix3d rot =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  Eigen::VectorXd q, qr;
  const Model m = grid(8, 8, 0.5, 0.4, q, [](Eigen::Vector3d p) { return p; });
  const Model mr = grid(8, 8, 0.5, 0.4, qr, [&](Eigen::Vector3d p) {
    return Eigen::Vector3d(rot * p + Eigen::Vector3d(3, -1, 2));
  });
  const FabricShape a = measure_fabric(m, q), b = measure_fabric(mr, qr);
  EXPECT_NEAR(a.course_extent_cm, b.course_extent_cm, 1e-9);
  EXPECT_NEAR(a.wale_extent_cm, b.wale_extent_cm, 1e-9);
  EXPECT_NEAR(a.thickness_cm, b.thickness_cm, 1e-9);
  EXPECT_NEAR(b.course_axis.dot(rot * Eigen::Vector3d::UnitX()), 1.0, 1e-9);
}

// Side edges rolled toward the back (as stockinette's do): the curl shows, with the sign
// of the side, and the course extent shrinks.
TEST(FabricShape, RolledSideEdgesShowAsCurl) {
  const double w = 0.5, width = 12 * w;
  auto roll = [&](Eigen::Vector3d p) {
    // within 1 cm of either side edge, wrap the sheet around a cylinder of radius 0.4 cm
    const double rc = 0.4;
    for (int side : {0, 1}) {
      const double edge = side == 0 ? 1.0 : width - 1.0;
      const double beyond = side == 0 ? edge - p.x() : p.x() - edge;
      if (beyond > 0) {
        const double a = beyond / rc;
        const double dx = rc * std::sin(a);
        p.x() = side == 0 ? edge - dx : edge + dx;
        p.z() = -rc * (1 - std::cos(a));
      }
    }
    return p;
  };
  Eigen::VectorXd q, qf;
  const Model m = grid(12, 12, w, 0.4, q, roll);
  const Model flat = grid(12, 12, w, 0.4, qf, [](Eigen::Vector3d p) { return p; });
  const FabricShape s = measure_fabric(m, q), f = measure_fabric(flat, qf);
  EXPECT_GT(s.edge_curl, 0.2);
  EXPECT_LT(s.edge_offset_cm[0], -0.1) << "left edge rolls to the back";
  EXPECT_LT(s.edge_offset_cm[1], -0.1) << "right edge rolls to the back";
  // the bottom edge is straight; only its two rolled corners pull its mean offset back
  EXPECT_LT(std::abs(s.edge_offset_cm[2]), 0.5 * std::abs(s.edge_offset_cm[0]));
  EXPECT_LT(s.course_extent_cm, f.course_extent_cm - 0.5);
  // measured along the fabric, the rolled sheet is nearly as wide as the flat one: chords
  // over 4 stitches cut across this tight roll (circumference 2.5 cm), but never exceed it
  EXPECT_LE(s.course_length_cm, f.course_length_cm + 1e-9);
  EXPECT_GT(s.course_length_cm, 0.85 * f.course_length_cm);
  EXPECT_GT(s.course_length_cm, s.course_extent_cm + 0.5);
}

TEST(FabricShape, RejectsModelsWithoutStitches) {
  ModelBuilder b;
  b.add_yarn(Eigen::Matrix3Xd::Random(3, 8));
  const Model m = b.build(Params{});
  EXPECT_THROW(measure_fabric(m, b.positions()), std::invalid_argument);
}

}  // namespace
}  // namespace knit
