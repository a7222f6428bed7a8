// Physics of the sheet solver (src/knit/sheet/sheet_solver.hpp): small-strain uniaxial
// tension against the analytic modulus in both material directions, a hanging sheet that
// comes to rest holding its weight, stability at a large step, and momentum conservation.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "fd_check.hpp"
#include "knit/sheet/bw_energy.hpp"
#include "knit/sheet/sheet.hpp"
#include "knit/sheet/sheet_solver.hpp"

namespace knit::sheet {
namespace {

double max_edge_strain(const SheetMesh& mesh, const Eigen::VectorXd& x) {
  double m = 0;
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      const double rest = (mesh.rest.col(a) - mesh.rest.col(b)).norm();
      m = std::max(m, std::abs((x.segment<3>(3 * a) - x.segment<3>(3 * b)).norm() / rest - 1));
    }
  return m;
}

// Uniaxial tension. With E = ½ k a (‖w‖ − 1)² per triangle and direction (bw_energy.hpp,
// k = k_stretch_u or k_stretch_v), a strip of rest length L (along the pull) and width W
// stretched uniformly to strain ε stores E = ½ k (W L) ε²; the clamp force is
// F = dE/d(εL) = k W ε, exactly (the stretch condition is linear in ‖w‖, so this holds at
// finite ε too): k is the 2-D Young modulus along the pull, whatever the mesh. The uniform state is
// the exact equilibrium of the mesh: the stretch forces on a node sum ∫∂φᵢ/∂u dA, which vanishes on
// interior and free lateral boundary nodes, and the conditions along the other direction and the
// shear stay at rest. What we find: no lateral contraction at all (Poisson ratio 0), since nothing
// couples w_u to w_v.
void check_uniaxial(bool along_u) {
  const double length = 6.0, width = 2.5;  // cm, along and across the pull
  const SheetMesh mesh = along_u ? make_rectangle(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(),
                                                  Eigen::Vector3d::UnitY(), length, width, 13, 6)
                                 : make_rectangle(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(),
                                                  Eigen::Vector3d::UnitY(), width, length, 6, 13);
  SheetMaterial mat;      // with shear and bending; anisotropic stretch
  mat.k_stretch_u = 1e5;  // dyn/cm
  mat.k_stretch_v = 3e5;
  const Eigen::Vector3d pull = along_u ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  std::vector<SheetConstraint> clamps(2);
  clamps[0].name = "fixed";
  clamps[1].name = "pulled";
  clamps[0].nodes = along_u ? grid_column(mesh, 0) : grid_row(mesh, 0);
  clamps[1].nodes = along_u ? grid_column(mesh, mesh.nu - 1) : grid_row(mesh, mesh.nv - 1);
  StaticSettings settings;
  settings.gravity.setZero();

  SheetState state = rest_state(mesh);
  const double strain_steps[] = {1e-3, 0.02, 0.05};  // small strain, then larger increments
  double strain = 0;
  for (double target : strain_steps) {
    clamps[1].velocity = (target - strain) * length * pull;
    move_constraints({clamps[1]}, 1.0, state);  // displace the pulled clamp
    strain = target;
    const StaticReport r = solve_static(mesh, mat, clamps, settings, state);
    ASSERT_TRUE(r.converged) << "strain " << strain << ": residual " << r.residual;
    const double expected = (along_u ? mat.k_stretch_u : mat.k_stretch_v) * width * strain;
    const std::string what = std::string(along_u ? "u" : "v") + " strain " + std::to_string(strain);
    EXPECT_NEAR(r.reactions[1].dot(pull), expected, 0.02 * expected) << what;
    EXPECT_NEAR(r.reactions[0].dot(pull), -expected, 0.02 * expected) << what;
    EXPECT_LT((r.reactions[0] + r.reactions[1]).norm(), 1e-6 * expected) << what;
    // no Poisson contraction: the width is unchanged
    const Eigen::Vector3d across = along_u ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitX();
    double lo = 1e300, hi = -1e300;
    for (int i = 0; i < mesh.num_nodes(); ++i) {
      lo = std::min(lo, state.positions.segment<3>(3 * i).dot(across));
      hi = std::max(hi, state.positions.segment<3>(3 * i).dot(across));
    }
    EXPECT_NEAR(hi - lo, width, 1e-9 * width) << what;
  }
}

TEST(SheetStatics, UniaxialTensionAlongUMatchesTheModulus) {
  check_uniaxial(true);
}
TEST(SheetStatics, UniaxialTensionAlongVMatchesTheModulus) {
  check_uniaxial(false);
}

// a 10 cm × 10 cm sheet hanging in the x–z plane from its top row
SheetMesh hanging_mesh() {
  return make_rectangle(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(),
                        -Eigen::Vector3d::UnitZ(), 10.0, 10.0, 9, 9);
}

TEST(SheetDynamics, HangingSheetComesToRestHoldingItsWeight) {
  const SheetMesh mesh = hanging_mesh();
  const SheetMaterial mat;
  std::vector<SheetConstraint> clamp{{"top", grid_row(mesh, 0), Eigen::Vector3d::Zero()}};
  StepSettings settings;
  settings.h = 1e-3;
  SheetState state = rest_state(mesh);
  double peak = 0, last = 0;
  StepReport r;
  for (int s = 0; s < 300; ++s) {
    r = step_implicit_euler(mesh, mat, clamp, settings, state);
    peak = std::max(peak, r.kinetic_energy);
    last = r.kinetic_energy;
    ASSERT_GT(r.cg_iterations, 0);
  }
  EXPECT_NEAR(state.time, 0.3, 1e-12);
  EXPECT_GT(peak, 0.0);
  EXPECT_LT(last, 1e-6 * peak) << "kinetic energy has not decayed";
  // at rest the clamp carries the sheet's weight, upward
  const double weight = mesh.mass.sum() * 981;
  EXPECT_NEAR(r.reactions[0].z(), weight, 0.01 * weight);
  EXPECT_LT(std::hypot(r.reactions[0].x(), r.reactions[0].y()), 0.01 * weight);
  // and the state is the static equilibrium
  SheetState stat = state;
  const StaticReport sr = solve_static(mesh, mat, clamp, StaticSettings{}, stat);
  ASSERT_TRUE(sr.converged);
  EXPECT_NEAR(sr.reactions[0].z(), weight, 1e-6 * weight);
  EXPECT_LT((stat.positions - state.positions).cwiseAbs().maxCoeff(), 1e-4);
}

TEST(SheetDynamics, LargeStepIsStableAndDissipative) {
  // a horizontal sheet held along one edge swings down under gravity at h = 10 ms
  const SheetMesh mesh = make_rectangle(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(),
                                        Eigen::Vector3d::UnitY(), 10.0, 10.0, 9, 9);
  const SheetMaterial mat;
  std::vector<SheetConstraint> clamp{{"edge", grid_column(mesh, 0), Eigen::Vector3d::Zero()}};
  StepSettings settings;
  settings.h = 1e-2;
  SheetState state = rest_state(mesh);
  double total0 = 0;
  for (int s = 0; s < 100; ++s) {
    const StepReport r = step_implicit_euler(mesh, mat, clamp, settings, state);
    ASSERT_TRUE(state.positions.allFinite());
    const double total = r.kinetic_energy + potential_energy(mesh, mat, state.positions);
    if (s == 0) total0 = r.potential_energy;
    // implicit Euler only loses energy (a small slack for the linearisation)
    EXPECT_LE(total, total0 + 1e-3 * std::abs(total0)) << "step " << s;
    EXPECT_LT(max_edge_strain(mesh, state.positions), 0.05) << "step " << s;
  }
  // it swung down: the free edge is well below the clamp
  EXPECT_LT(state.positions[3 * grid_node(mesh, 8, 4) + 2], -5.0);
}

TEST(SheetDynamics, FreeSheetKeepsItsMomentum) {
  const SheetMesh mesh = make_rectangle(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(),
                                        Eigen::Vector3d::UnitY(), 4.0, 3.0, 5, 4);
  const SheetMaterial mat;
  SheetState state = rest_state(mesh);
  state.positions = test::jitter(state.positions, 0.1, 3);
  state.velocities = test::jitter(state.velocities, 20.0, 4);
  StepSettings settings;
  settings.h = 1e-3;
  settings.gravity.setZero();
  auto momentum = [&] {
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    for (int i = 0; i < mesh.num_nodes(); ++i)
      p += mesh.mass[i] * state.velocities.segment<3>(3 * i);
    return p;
  };
  double scale = 0;
  for (int i = 0; i < mesh.num_nodes(); ++i)
    scale += mesh.mass[i] * state.velocities.segment<3>(3 * i).norm();
  const Eigen::Vector3d p0 = momentum();
  for (int s = 0; s < 20; ++s) step_implicit_euler(mesh, mat, {}, settings, state);
  EXPECT_LT((momentum() - p0).norm(), 1e-8 * scale);
  // it did deform: the internal forces acted
  EXPECT_GT(
      (state.velocities - test::jitter(Eigen::VectorXd::Zero(mesh.num_dofs()), 20.0, 4)).norm(),
      1.0);
}

TEST(SheetDynamics, ConstrainedNodesFollowTheirPrescribedVelocity) {
  const SheetMesh mesh = hanging_mesh();
  const Eigen::Vector3d vel(0, 0, 5.0);  // cm/s, lifting
  std::vector<SheetConstraint> clamp{{"top", grid_row(mesh, 0), vel}};
  SheetState state = rest_state(mesh);
  StepSettings settings;
  for (int s = 0; s < 10; ++s) step_implicit_euler(mesh, SheetMaterial{}, clamp, settings, state);
  for (int i : clamp[0].nodes)
    EXPECT_LT(
        (state.positions.segment<3>(3 * i) - (mesh.rest.col(i) + 10 * settings.h * vel)).norm(),
        1e-12);
}

TEST(SheetDynamics, BadInputThrows) {
  const SheetMesh mesh = hanging_mesh();
  SheetState state = rest_state(mesh);
  StepSettings settings;
  settings.h = 0;
  EXPECT_THROW(step_implicit_euler(mesh, {}, {}, settings, state), std::invalid_argument);
  settings.h = 1e-3;
  std::vector<SheetConstraint> bad{{"a", {0, 1}, {}}, {"b", {1}, {}}};
  EXPECT_THROW(step_implicit_euler(mesh, {}, bad, settings, state), std::invalid_argument);
  bad = {{"a", {mesh.num_nodes()}, {}}};
  EXPECT_THROW(step_implicit_euler(mesh, {}, bad, settings, state), std::invalid_argument);
  EXPECT_THROW(solve_static(mesh, {}, bad, {}, state), std::invalid_argument);
}

}  // namespace
}  // namespace knit::sheet
