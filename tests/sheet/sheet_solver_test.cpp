// Physics of the sheet solver (src/knit/sheet/sheet_solver.hpp): small-strain uniaxial
// tension against the analytic modulus in both material directions, a hanging sheet that
// comes to rest holding its weight, stability at a large step, momentum conservation, and a
// bias pull whose flat state is a saddle that the projected Newton statics leaves.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <array>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "fd_check.hpp"
#include "knit/sheet/bw_energy.hpp"
#include "knit/sheet/sheet.hpp"
#include "knit/sheet/sheet_solver.hpp"

namespace knit::sheet {
namespace {

// clamps on the 2 × 2 nodes at opposite corners of a 9 × 9-node square: a bias pull
std::vector<SheetConstraint> diagonal_clamps(const SheetMesh& mesh) {
  auto corner = [&](int i0, int j0) {
    std::vector<int> nodes;
    for (int j = j0; j < j0 + 2; ++j)
      for (int i = i0; i < i0 + 2; ++i) nodes.push_back(j * mesh.nu + i);
    return nodes;
  };
  return {{"fixed", corner(0, 0), Eigen::Vector3d::Zero()},
          {"moving", corner(7, 7), Eigen::Vector3d::Zero()}};
}

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
  for (Jacobians kind : {Jacobians::PSD, Jacobians::PROJECTED}) {
    StaticSettings settings;
    settings.gravity.setZero();
    settings.hessian = kind;

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
      const std::string what = std::string(along_u ? "u" : "v") + " strain " +
                               std::to_string(strain) +
                               (kind == Jacobians::PSD ? " (PSD)" : " (projected)");
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
      if (kind == Jacobians::PROJECTED) EXPECT_TRUE(r.stable) << what;
    }
  }
}

TEST(SheetStatics, UniaxialTensionAlongUMatchesTheModulus) {
  check_uniaxial(true);
}
TEST(SheetStatics, UniaxialTensionAlongVMatchesTheModulus) {
  check_uniaxial(false);
}

// A square pulled along its diagonal by clamps at two opposite corners (the bias test of
// `knitsim stretch --sheet`): it stretches along the pull and is compressed across it. Flat,
// that is a saddle of the energy — a thin sheet wrinkles out of its plane to relieve the
// compression. BW's PSD (Gauss–Newton) Hessian has no negative curvature to see this and
// stops on the flat saddle; the projected Newton iteration (the exact Hessian where it is
// positive definite, each element's projection where not) goes on to a stable minimum,
// lower in energy, where the exact Hessian on the free nodes is positive semi-definite.
TEST(SheetStatics, BiasPullWrinklesToAStableMinimumBelowTheFlatSaddle) {
  const double side = 10.0;
  const SheetMesh mesh = make_rectangle(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(),
                                        Eigen::Vector3d::UnitY(), side, side, 9, 9);
  SheetMaterial mat;
  mat.k_stretch_u = 3e3;  // dyn/cm: shear as stiff as stretch, as the 42×32 knits' fit asks
  mat.k_stretch_v = 3e3;
  mat.k_shear = 3e3;
  mat.k_bend = 1e-2;  // erg: a thin sheet
  const std::vector<SheetConstraint> clamps = diagonal_clamps(mesh);
  std::vector<bool> held(mesh.num_nodes(), false);
  for (const SheetConstraint& c : clamps)
    for (int n : c.nodes) held[n] = true;
  // the smallest eigenvalue of the exact Hessian on the free nodes, relative to its largest
  auto lowest_curvature = [&](const Eigen::VectorXd& x) {
    const Eigen::MatrixXd h =
        -Eigen::MatrixXd(evaluate_forces(mesh, mat, x, Eigen::VectorXd::Zero(x.size()),
                                         Eigen::Vector3d::Zero(), Jacobians::EXACT)
                             .dfdx);
    std::vector<int> free;
    for (int n = 0; n < mesh.num_nodes(); ++n)
      if (!held[n])
        for (int d = 0; d < 3; ++d) free.push_back(3 * n + d);
    Eigen::MatrixXd hf(free.size(), free.size());
    for (size_t r = 0; r < free.size(); ++r)
      for (size_t c = 0; c < free.size(); ++c) hf(r, c) = h(free[r], free[c]);
    const Eigen::VectorXd e = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(hf).eigenvalues();
    return e.minCoeff() / e.cwiseAbs().maxCoeff();
  };
  const Eigen::Vector3d axis = Eigen::Vector3d(1, 1, 0).normalized();
  std::array<SheetState, 2> states;
  std::array<StaticReport, 2> reports;
  const Jacobians kinds[2] = {Jacobians::PROJECTED, Jacobians::PSD};
  for (int k = 0; k < 2; ++k) {
    SheetState& state = states[k];
    state = rest_state(mesh);
    for (int n : clamps[1].nodes) state.positions.segment<3>(3 * n) += 0.15 * side * axis;
    StaticSettings settings;
    settings.gravity.setZero();
    settings.max_iterations = 2000;
    settings.force_tolerance = 1e-9 * mat.k_shear * side;
    settings.hessian = kinds[k];
    reports[k] = solve_static(mesh, mat, clamps, settings, state);
    const char* name = k == 0 ? "projected" : "PSD";
    ASSERT_TRUE(reports[k].converged) << name << ": residual " << reports[k].residual << " after "
                                      << reports[k].iterations << " iterations";
    const double force = reports[k].reactions[1].dot(axis);
    EXPECT_GT(force, 0.0) << name;
    EXPECT_LT((reports[k].reactions[0] + reports[k].reactions[1]).norm(), 1e-6 * force) << name;
  }
  double out_of_plane = 0;
  for (int n = 0; n < mesh.num_nodes(); ++n)
    out_of_plane = std::max(out_of_plane, std::abs(states[0].positions[3 * n + 2]));
  EXPECT_GT(out_of_plane, 0.01 * side) << "the projected solve did not leave the plane";
  EXPECT_TRUE(reports[0].stable);
  EXPECT_FALSE(reports[1].stable);  // PSD does not look
  // started on the flat saddle itself, where the force is already within tolerance, the
  // projected solve must see the saddle and leave it along its negative curvature
  {
    SheetState from_saddle = states[1];
    StaticSettings settings;
    settings.hessian = Jacobians::PROJECTED;
    settings.gravity.setZero();
    settings.max_iterations = 2000;
    settings.force_tolerance = 1e-9 * mat.k_shear * side;
    const StaticReport r = solve_static(mesh, mat, clamps, settings, from_saddle);
    ASSERT_TRUE(r.converged) << "from the saddle: residual " << r.residual;
    EXPECT_GE(r.escapes, 1) << "it did not see the saddle";
    EXPECT_TRUE(r.stable);
    EXPECT_LT(r.energy, 0.99 * reports[1].energy);
    EXPECT_GT(lowest_curvature(from_saddle.positions), -1e-9);
  }
  EXPECT_LT(reports[0].energy, 0.99 * reports[1].energy);
  EXPECT_LT(lowest_curvature(states[1].positions), -1e-4) << "the flat state is not a saddle";
  EXPECT_GT(lowest_curvature(states[0].positions), -1e-9) << "the wrinkled state is not a minimum";
  std::printf(
      "bias pull: projected Newton %d iterations to %.4f erg (wrinkled %.3f cm out of "
      "plane), PSD %d to the flat saddle at %.4f erg\n",
      reports[0].iterations, reports[0].energy, out_of_plane, reports[1].iterations,
      reports[1].energy);
}

// The same bias pull with shear 15–20× softer than stretch (the 12×12 stockinette's fit),
// on to strain 0.8. Past strain √2 − 1 the diagonal between the clamps is longer than the
// two sides of a triangle it crosses, so the sheet's triangles along it must stretch or
// collapse; with a soft shear its minimum collapses some of them (their area falls below a
// third of its rest value). There BW's bend condition θ − θ₀ has a force ∝ 1/area, and the
// projected Newton iteration failed every sample past 0.4; weighted by the triangles'
// areas (bw_energy.hpp) it stays bounded, and every sample converges to a stable
// minimum. Each sample's clamp force is checked against the energy: at a minimum it is the
// derivative of the energy with respect to the moving clamp's position.
TEST(SheetStatics, SoftShearedBiasPullConvergesPastTriangleCollapse) {
  const double side = 10.0;
  const SheetMesh mesh = make_rectangle(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(),
                                        Eigen::Vector3d::UnitY(), side, side, 9, 9);
  SheetMaterial mat;
  mat.k_stretch_u = 1048;  // dyn/cm
  mat.k_stretch_v = 1493;
  mat.k_shear = 71;
  mat.k_bend = 1.0;  // erg, the stretch recipe's default
  const std::vector<SheetConstraint> clamps = diagonal_clamps(mesh);
  const Eigen::Vector3d axis = Eigen::Vector3d(1, 1, 0).normalized();
  const double separation = (mesh.rest.col(7 * mesh.nu + 7) - mesh.rest.col(0)).norm();
  const Eigen::VectorXd rest = mesh.rest_positions();
  StaticSettings settings;
  settings.gravity.setZero();
  settings.max_iterations = 2000;
  settings.force_tolerance = 1e-9 * mat.k_stretch_v * side;
  settings.hessian = Jacobians::PROJECTED;
  // the sheet in equilibrium with the moving clamp at `strain`, from `state`
  auto solve = [&](double strain, SheetState& state) {
    for (int n : clamps[1].nodes)
      state.positions.segment<3>(3 * n) = rest.segment<3>(3 * n) + strain * separation * axis;
    return solve_static(mesh, mat, clamps, settings, state);
  };
  SheetState state = rest_state(mesh);
  double previous_force = 0, smallest_area = 1;
  for (int step = 1; step <= 16; ++step) {
    const double strain = 0.05 * step;
    const std::string what = "strain " + std::to_string(strain);
    const StaticReport r = solve(strain, state);
    ASSERT_TRUE(r.converged) << what << ": residual " << r.residual << " after " << r.iterations
                             << " iterations";
    EXPECT_TRUE(r.stable) << what;
    const double force = r.reactions[1].dot(axis);
    EXPECT_GT(force, previous_force) << what;
    EXPECT_LT((r.reactions[0] + r.reactions[1]).norm(), 1e-6 * force) << what;
    previous_force = force;
    // the force is the energy's slope: central differences from this minimum
    const double de = 1e-4;
    SheetState lo = state, hi = state;
    const StaticReport rl = solve(strain - de, lo), rh = solve(strain + de, hi);
    ASSERT_TRUE(rl.converged && rh.converged) << what;
    const double slope = (rh.energy - rl.energy) / (2 * de * separation);
    EXPECT_NEAR(force, slope, 1e-3 * force) << what;
  }
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    const Eigen::Vector3d a = state.positions.segment<3>(3 * tri[0]),
                          b = state.positions.segment<3>(3 * tri[1]),
                          c = state.positions.segment<3>(3 * tri[2]);
    smallest_area = std::min(smallest_area, 0.5 * (b - a).cross(c - a).norm() / mesh.area[t]);
  }
  EXPECT_LT(smallest_area, 1.0 / 3) << "no triangle collapsed: the test does not reach the case";
  std::printf(
      "soft-sheared bias pull to strain 0.8: %.1f dyn, smallest triangle %.3f of its "
      "rest area\n",
      previous_force, smallest_area);
}

TEST(SheetStatics, SolveStaticRejectsAHessianItCannotUse) {
  const SheetMesh mesh = make_rectangle(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(),
                                        Eigen::Vector3d::UnitY(), 2.0, 2.0, 3, 3);
  SheetState state = rest_state(mesh);
  for (Jacobians bad : {Jacobians::NONE, Jacobians::EXACT}) {
    StaticSettings settings;
    settings.hessian = bad;
    EXPECT_THROW(solve_static(mesh, SheetMaterial{}, {}, settings, state), std::invalid_argument);
  }
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
