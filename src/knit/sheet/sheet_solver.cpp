#include "knit/sheet/sheet_solver.hpp"

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>

namespace knit::sheet {

namespace {

// constraint index of every node (−1: free); validates the constraints
std::vector<int> constraint_owner(const SheetMesh& mesh,
                                  const std::vector<SheetConstraint>& constraints) {
  std::vector<int> owner(mesh.num_nodes(), -1);
  for (size_t s = 0; s < constraints.size(); ++s) {
    const SheetConstraint& c = constraints[s];
    const std::string label = "constraint " + std::to_string(s) +
                              (c.name.empty() ? std::string() : " ('" + c.name + "')");
    if (!c.velocity.allFinite()) throw std::invalid_argument(label + ": velocity must be finite");
    for (int i : c.nodes) {
      if (i < 0 || i >= mesh.num_nodes())
        throw std::invalid_argument(label + ": node " + std::to_string(i) + " out of [0, " +
                                    std::to_string(mesh.num_nodes()) + ")");
      if (owner[i] >= 0)
        throw std::invalid_argument(label + ": node " + std::to_string(i) +
                                    " is already in constraint " + std::to_string(owner[i]));
      owner[i] = static_cast<int>(s);
    }
  }
  return owner;
}

// free index of every DOF (−1: constrained)
std::vector<int> free_dofs(const std::vector<int>& owner, int& n_free) {
  std::vector<int> map(3 * owner.size(), -1);
  n_free = 0;
  for (size_t i = 0; i < owner.size(); ++i)
    if (owner[i] < 0)
      for (int r = 0; r < 3; ++r) map[3 * i + r] = n_free++;
  return map;
}

// the free rows and columns of a
Eigen::SparseMatrix<double> restrict_matrix(const Eigen::SparseMatrix<double>& a,
                                            const std::vector<int>& map, int n_free) {
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(a.nonZeros());
  for (int col = 0; col < a.outerSize(); ++col) {
    if (map[col] < 0) continue;
    for (Eigen::SparseMatrix<double>::InnerIterator it(a, col); it; ++it)
      if (map[it.row()] >= 0) t.emplace_back(map[it.row()], map[col], it.value());
  }
  Eigen::SparseMatrix<double> r(n_free, n_free);
  r.setFromTriplets(t.begin(), t.end());
  return r;
}

// The free rows and columns of matrices that share one pattern (the sheet's Jacobians, whose
// pattern is the mesh's), set up once and refilled in place: `matrix` holds the pattern,
// `source[k]` the index in the full matrix's values of its k-th value (−1: a diagonal entry
// the full pattern lacks, kept for the regularisation), `diagonal` the indices of its (i, i)
// entries. The free indices keep the full ones' order, so the restricted entries come in the
// full matrix's column-major order (its row indices sorted within each column, as Eigen
// keeps them).
struct FreeBlock {
  Eigen::SparseMatrix<double> matrix;
  std::vector<int> source, diagonal;
  Eigen::Index full_nonzeros = 0;

  FreeBlock(const Eigen::SparseMatrix<double>& a, const std::vector<int>& map, int n_free)
      : full_nonzeros(a.nonZeros()) {
    const int* full_outer = a.outerIndexPtr();
    const int* full_inner = a.innerIndexPtr();
    std::vector<int> outer(n_free + 1, 0), inner;
    for (int col = 0; col < a.outerSize(); ++col) {
      const int c = map[col];
      if (c < 0) continue;
      bool has_diagonal = false;
      auto add = [&](int row, int src) {
        if (row == c) {
          diagonal.push_back(static_cast<int>(inner.size()));
          has_diagonal = true;
        }
        inner.push_back(row);
        source.push_back(src);
      };
      for (int k = full_outer[col]; k < full_outer[col + 1]; ++k) {
        const int row = map[full_inner[k]];
        if (row < 0) continue;
        if (!has_diagonal && row > c) add(c, -1);
        add(row, k);
      }
      if (!has_diagonal) add(c, -1);
      outer[c + 1] = static_cast<int>(inner.size());
    }
    std::vector<double> values(inner.size(), 0.0);
    matrix = Eigen::Map<const Eigen::SparseMatrix<double>>(
        n_free, n_free, static_cast<Eigen::Index>(inner.size()), outer.data(), inner.data(),
        values.data());
  }
  // matrix ← scale · a restricted, plus mu on the diagonal
  void fill(const Eigen::SparseMatrix<double>& a, double scale, double mu) {
    double* v = matrix.valuePtr();
    const double* src = a.valuePtr();
    for (size_t k = 0; k < source.size(); ++k) v[k] = source[k] < 0 ? 0.0 : scale * src[source[k]];
    if (mu > 0)
      for (int k : diagonal) v[k] += mu;
  }
};

Eigen::VectorXd restrict_vector(const Eigen::VectorXd& v, const std::vector<int>& map, int n_free) {
  Eigen::VectorXd r(n_free);
  for (size_t k = 0; k < map.size(); ++k)
    if (map[k] >= 0) r[map[k]] = v[k];
  return r;
}

void check_state(const SheetMesh& mesh, const SheetState& state, const char* who) {
  const Eigen::Index n = mesh.num_dofs();
  if (state.positions.size() != n)
    throw std::invalid_argument(std::string(who) + ": state.positions has " +
                                std::to_string(state.positions.size()) + " entries, expected " +
                                std::to_string(n));
  if (state.velocities.size() != n)
    throw std::invalid_argument(std::string(who) + ": state.velocities has " +
                                std::to_string(state.velocities.size()) + " entries, expected " +
                                std::to_string(n));
}

// −Σ f over each constraint's nodes
std::vector<Eigen::Vector3d> sum_per_constraint(const std::vector<SheetConstraint>& constraints,
                                                const Eigen::VectorXd& per_dof) {
  std::vector<Eigen::Vector3d> r(constraints.size(), Eigen::Vector3d::Zero());
  for (size_t s = 0; s < constraints.size(); ++s)
    for (int i : constraints[s].nodes) r[s] += per_dof.segment<3>(3 * i);
  return r;
}

// x moved by scale · d on the free DOFs (d holds one entry per free DOF)
Eigen::VectorXd moved_free(const Eigen::VectorXd& x, const Eigen::VectorXd& d, double scale,
                           const std::vector<int>& map) {
  Eigen::VectorXd xt = x;
  for (size_t k = 0; k < map.size(); ++k)
    if (map[k] >= 0) xt[k] += scale * d[map[k]];
  return xt;
}

double max_abs_free(const Eigen::VectorXd& f, const std::vector<int>& map) {
  double m = 0;
  for (size_t k = 0; k < map.size(); ++k)
    if (map[k] >= 0) m = std::max(m, std::abs(f[k]));
  return m;
}

}  // namespace

SheetState rest_state(const SheetMesh& mesh) {
  SheetState s;
  s.positions = mesh.rest_positions();
  s.velocities = Eigen::VectorXd::Zero(mesh.num_dofs());
  return s;
}

void move_constraints(const std::vector<SheetConstraint>& constraints, double dt,
                      SheetState& state) {
  for (size_t s = 0; s < constraints.size(); ++s)
    for (int i : constraints[s].nodes) {
      if (i < 0 || 3 * i + 2 >= state.positions.size())
        throw std::invalid_argument("move_constraints: constraint " + std::to_string(s) +
                                    " names node " + std::to_string(i) + ", out of range");
      state.positions.segment<3>(3 * i) += dt * constraints[s].velocity;
    }
}

StepReport step_implicit_euler(const SheetMesh& mesh, const SheetMaterial& material,
                               const std::vector<SheetConstraint>& constraints,
                               const StepSettings& settings, SheetState& state) {
  const double h = settings.h;
  if (!(h > 0) || !std::isfinite(h))
    throw std::invalid_argument("step_implicit_euler: time step h must be positive, got " +
                                std::to_string(h));
  check_state(mesh, state, "step_implicit_euler");
  const std::vector<int> owner = constraint_owner(mesh, constraints);
  int n_free = 0;
  const std::vector<int> map = free_dofs(owner, n_free);
  const int n = mesh.num_nodes();
  const Eigen::VectorXd& x0 = state.positions;
  const Eigen::VectorXd& v0 = state.velocities;

  const SheetForces f = evaluate_forces(mesh, material, x0, v0, settings.gravity, Jacobians::PSD);
  Eigen::VectorXd mass(3 * n);
  for (int i = 0; i < n; ++i) mass.segment<3>(3 * i).setConstant(mesh.mass[i]);

  // A = M − h D − h² K,  b = h (f₀ + h K v₀)
  Eigen::SparseMatrix<double> a = -h * f.dfdv - (h * h) * f.dfdx;
  {
    Eigen::SparseMatrix<double> m(3 * n, 3 * n);
    std::vector<Eigen::Triplet<double>> t;
    for (int k = 0; k < 3 * n; ++k) t.emplace_back(k, k, mass[k]);
    m.setFromTriplets(t.begin(), t.end());
    a += m;
  }
  const Eigen::VectorXd b = h * (f.force + h * (f.dfdx * v0));

  // prescribed Δv of the constrained nodes
  Eigen::VectorXd dv = Eigen::VectorXd::Zero(3 * n);
  for (int i = 0; i < n; ++i)
    if (owner[i] >= 0) dv.segment<3>(3 * i) = constraints[owner[i]].velocity - v0.segment<3>(3 * i);

  StepReport report;
  report.potential_energy = f.energy();
  if (n_free > 0) {
    const Eigen::SparseMatrix<double> aff = restrict_matrix(a, map, n_free);
    const Eigen::VectorXd rhs = restrict_vector(b - a * dv, map, n_free);
    Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper,
                             Eigen::DiagonalPreconditioner<double>>
        cg;
    cg.setTolerance(settings.cg_tolerance);
    cg.setMaxIterations(settings.cg_max_iterations);
    cg.compute(aff);
    const Eigen::VectorXd dvf = cg.solve(rhs);
    report.cg_iterations = static_cast<int>(cg.iterations());
    report.cg_error = cg.error();
    if (cg.info() != Eigen::Success || !dvf.allFinite())
      throw std::runtime_error("step_implicit_euler at t = " + std::to_string(state.time) +
                               ": conjugate gradient did not converge (" +
                               std::to_string(report.cg_iterations) + " iterations, residual " +
                               std::to_string(report.cg_error) + "); state kept");
    for (size_t k = 0; k < map.size(); ++k)
      if (map[k] >= 0) dv[k] = dvf[map[k]];
  }

  // reaction = (A Δv − b)/h on the constrained rows = m a − f (linearised)
  report.reactions = sum_per_constraint(constraints, (a * dv - b) / h);

  Eigen::VectorXd v1 = v0 + dv;
  for (int i = 0; i < n; ++i)
    if (owner[i] >= 0) v1.segment<3>(3 * i) = constraints[owner[i]].velocity;  // exactly
  const Eigen::VectorXd x1 = x0 + h * v1;
  if (!x1.allFinite() || !v1.allFinite())
    throw std::runtime_error("step_implicit_euler at t = " + std::to_string(state.time) +
                             ": the step produced non-finite values; state kept");
  state.positions = x1;
  state.velocities = v1;
  state.time += h;
  report.kinetic_energy = 0.5 * v1.cwiseProduct(v1).dot(mass);
  return report;
}

StaticReport solve_static(const SheetMesh& mesh, const SheetMaterial& material,
                          const std::vector<SheetConstraint>& constraints,
                          const StaticSettings& settings, SheetState& state) {
  if (settings.max_iterations < 0)
    throw std::invalid_argument("solve_static: max_iterations must be >= 0");
  if (settings.hessian != Jacobians::PSD && settings.hessian != Jacobians::PROJECTED)
    throw std::invalid_argument("solve_static: hessian must be PSD or PROJECTED");
  check_state(mesh, state, "solve_static");
  const std::vector<int> owner = constraint_owner(mesh, constraints);
  int n_free = 0;
  const std::vector<int> map = free_dofs(owner, n_free);
  const Eigen::VectorXd zero_v = Eigen::VectorXd::Zero(mesh.num_dofs());
  const Eigen::Vector3d g = settings.gravity;

  Eigen::VectorXd x = state.positions;
  StaticReport report;
  double start_residual = -1;
  std::optional<FreeBlock> block;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
  // PROJECTED: each iteration tries the exact Hessian first (Newton's own step, quadratic
  // convergence near a stable state), shifted or projected where it is not positive
  // definite (below); the forces are evaluated with the exact Hessian
  const bool projected = settings.hessian == Jacobians::PROJECTED;
  const Jacobians first = projected ? Jacobians::EXACT : Jacobians::PSD;
  SheetForces f = evaluate_forces(mesh, material, x, zero_v, g, first), fp;
  // the free block of the pattern, and the factorisation's ordering, set up once: the pattern
  // is the mesh's every iteration
  auto setup_block = [&] {
    if (!f.dfdx.isCompressed() || (block && f.dfdx.nonZeros() != block->full_nonzeros))
      throw std::logic_error("solve_static: the sheet's Jacobian changed its pattern");
    if (!block) {
      block.emplace(f.dfdx, map, n_free);
      ldlt.analyzePattern(block->matrix);
    }
  };
  bool escaped = false;
  double shift = 0;  // the exact Hessian's diagonal shift in the iteration before
  double shortest_edge = std::numeric_limits<double>::infinity();  // rest, cm
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k)
      shortest_edge =
          std::min(shortest_edge, (mesh.rest.col(t[k]) - mesh.rest.col(t[(k + 1) % 3])).norm());
  double size = 0;  // the sheet's extent, cm: the scale of a step out of a saddle
  for (int d = 0; d < 3; ++d)
    size = std::max(size, x(Eigen::seqN(d, mesh.num_nodes(), 3)).maxCoeff() -
                              x(Eigen::seqN(d, mesh.num_nodes(), 3)).minCoeff());
  for (;;) {
    const double residual = max_abs_free(f.force, map);
    if (start_residual < 0) start_residual = residual;
    report.residual = residual;
    // after leaving a saddle, at least one Newton iteration before the next check
    if (!escaped && residual <= std::max(settings.force_tolerance,
                                         settings.relative_tolerance * start_residual)) {
      report.converged = true;
      if (!projected || n_free == 0) break;
      // An equilibrium: stable where the exact Hessian on the free nodes is positive
      // definite. Otherwise it is a saddle (a flat sheet compressed across a pull, which a
      // thin sheet leaves by wrinkling): leave it along the exact Hessian's direction of
      // negative curvature from its factorisation, z = P⁻¹ L⁻ᵀ eᵢ with zᵀ H z = Dᵢ < 0, by
      // the step along ±z that lowers the energy most, and iterate again.
      setup_block();
      block->fill(f.dfdx, -1, 0);
      ldlt.factorize(block->matrix);
      ++report.factorizations;
      if (ldlt.info() != Eigen::Success) break;  // singular: stability unknown
      Eigen::Index i = 0;
      if (ldlt.vectorD().minCoeff(&i) > 0) {
        report.stable = true;
        break;
      }
      if (report.escapes >= settings.max_escapes) break;
      Eigen::VectorXd y = Eigen::VectorXd::Unit(n_free, i);
      ldlt.matrixU().solveInPlace(y);
      Eigen::VectorXd z = ldlt.permutationPinv() * y;
      if (!z.allFinite() || !(z.cwiseAbs().maxCoeff() > 0)) break;
      z /= z.cwiseAbs().maxCoeff();
      const double e0 = f.energy();
      double best_e = e0;
      Eigen::VectorXd best;
      for (double step = 1e-6 * size; step <= 0.1 * size; step *= 4)
        for (double sign : {1.0, -1.0}) {
          Eigen::VectorXd xt = moved_free(x, z, sign * step, map);
          const double et = potential_energy(mesh, material, xt, g);
          if (std::isfinite(et) && et < best_e) {
            best_e = et;
            best = std::move(xt);
          }
        }
      if (best.size() == 0) {  // no lower energy along it: a minimum as far as round-off tells
        report.stable = true;
        break;
      }
      ++report.escapes;
      escaped = true;
      report.converged = false;
      x = std::move(best);
      evaluate_forces(mesh, material, x, zero_v, g, first, f);
      continue;
    }
    escaped = false;
    if (report.iterations >= settings.max_iterations) break;
    ++report.iterations;

    // Newton direction on the free DOFs: H d = f, H = −∂f/∂x (PSD, or the exact or projected
    // one)
    setup_block();
    const Eigen::VectorXd ff = restrict_vector(f.force, map, n_free);
    Eigen::VectorXd d;
    // the step from H with μ added to its diagonal, when H + μ is positive definite
    auto try_step = [&](const Eigen::SparseMatrix<double>& dfdx, double mu) {
      block->fill(dfdx, -1, mu);
      ldlt.factorize(block->matrix);
      ++report.factorizations;
      if (ldlt.info() != Eigen::Success) return false;
      d = ldlt.solve(ff);
      return d.allFinite() && d.dot(ff) > 0 && (ldlt.vectorD().array() > 0).all();
    };
    // PROJECTED: the exact Hessian, shifted by μ on its diagonal where it is not positive
    // definite (Levenberg–Marquardt: the shift of the iteration before, a quarter of it
    // first, grown fourfold until the factor is positive); the projected Hessian only where
    // a shift of 1e-3 of the diagonal does not do
    bool ok = false;
    if (projected) {
      block->fill(f.dfdx, -1, 0);
      const double diag = block->matrix.diagonal().cwiseAbs().maxCoeff();
      double mu = shift < 1e-9 * diag ? 0 : shift / 4;
      for (;;) {
        if ((ok = try_step(f.dfdx, mu))) break;
        mu = mu == 0 ? 1e-9 * diag : 4 * mu;
        if (mu > 1e-3 * diag) break;
      }
      shift = ok ? mu : 1e-3 * diag;
    }
    if (!ok) {
      const Eigen::SparseMatrix<double>* h = &f.dfdx;
      if (projected) {
        evaluate_forces(mesh, material, x, zero_v, g, Jacobians::PROJECTED, fp);
        h = &fp.dfdx;
        ++report.projected_iterations;
      }
      block->fill(*h, -1, 0);
      const double diag = block->matrix.diagonal().cwiseAbs().maxCoeff();
      for (double mu = 0; mu < 1e3 * diag && !ok; mu = (mu == 0 ? 1e-10 * diag : 100 * mu))
        ok = try_step(*h, mu);
    }
    if (!ok) break;

    // PROJECTED: no node moves more than half the shortest rest edge in one iteration (a
    // trust region). The BW energy lets a triangle fold over its neighbour for a bounded
    // bending energy, and a long step into a fold collapses triangles on the way, where the
    // bending force grows without bound
    if (projected) {
      double longest = 0;
      for (size_t k = 0; k + 2 < map.size(); k += 3) {
        double m2 = 0;
        for (int c = 0; c < 3; ++c)
          if (map[k + c] >= 0) m2 += d[map[k + c]] * d[map[k + c]];
        longest = std::max(longest, m2);
      }
      longest = std::sqrt(longest);
      if (longest > 0.5 * shortest_edge) {
        d *= 0.5 * shortest_edge / longest;
      }
    }
    // backtracking line search: Armijo on the energy, or (near the minimum, where the energy
    // change drowns in round-off) a decrease of the force residual
    const double e0 = f.energy(), slope = d.dot(ff), fnorm = ff.norm();
    bool accepted = false;
    for (double alpha = 1; alpha > 1e-8; alpha *= 0.5) {
      Eigen::VectorXd xt = moved_free(x, d, alpha, map);
      const double et = potential_energy(mesh, material, xt, g);
      bool accept = std::isfinite(et) && et <= e0 - 1e-4 * alpha * slope;
      SheetForces ft;
      // PROJECTED: the residual's test only where the energy did not rise beyond its
      // round-off (taken anywhere, it let a soft-sheared sheet climb into folds)
      if (!accept && std::isfinite(et) && (!projected || et <= e0 + 1e-12 * std::abs(e0))) {
        ft = evaluate_forces(mesh, material, xt, zero_v, g, Jacobians::NONE);
        accept = restrict_vector(ft.force, map, n_free).norm() < (1 - 1e-4 * alpha) * fnorm;
      }
      if (accept) {
        x = xt;
        accepted = true;
        break;
      }
    }
    if (!accepted) break;
    evaluate_forces(mesh, material, x, zero_v, g, first, f);
  }
  report.energy = f.energy();
  report.reactions = sum_per_constraint(constraints, -f.force);
  state.positions = x;
  state.velocities.setZero();
  return report;
}

}  // namespace knit::sheet
