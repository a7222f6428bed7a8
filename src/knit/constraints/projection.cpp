#include "knit/constraints/projection.hpp"

#include <tbb/parallel_for.h>

#include <Eigen/OrderingMethods>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <tuple>
#include <utility>
#include <vector>

#include "knit/constraints/inextensibility.hpp"

namespace knit {
namespace {

// largest |entry| as a plain loop (GCC 12 warns falsely inside Eigen's AVX-512 max
// reduction); NaN when any entry is NaN, so that a diverging projection is caught
double max_abs(const Eigen::VectorXd& v) {
  double m = 0;
  for (Eigen::Index k = 0; k < v.size(); ++k) {
    const double a = std::abs(v[k]);
    if (std::isnan(a)) return a;
    m = std::max(m, a);
  }
  return m;
}

}  // namespace

FastProjection::FastProjection(const Model& model) {
  std::vector<Eigen::Triplet<double>> trip, group_trip;
  m_group_row.push_back(0);
  for (const auto& group : model.constraint_groups) {
    const int row0 = m_group_row.back();
    group_trip.clear();
    group->jacobian_structure(model, group_trip);
    for (const auto& t : group_trip) trip.emplace_back(row0 + t.row(), t.col(), t.value());
    m_group_row.push_back(row0 + group->rows());
  }
  m_rows = m_group_row.back();
  m_G.resize(m_rows, model.num_dof());
  m_G.setFromTriplets(trip.begin(), trip.end());  // duplicates (shared control points) summed
  m_G.makeCompressed();
  m_lambda = Eigen::VectorXd::Zero(m_rows);
  build_normal_pattern(model.num_dof());
}

// A = G M⁻¹ Gᵀ has a fixed pattern: A_rc ≠ 0 only when rows r and c of G share a column k,
// and then A_rc = Σ_k G_rk G_ck / m_k over the shared columns. The fill-reducing ordering
// (AMD, as SimplicialLDLT would choose) is computed once here and A is assembled already
// permuted, Â = P A Pᵀ, upper triangle: then the natural-ordering factorisation reads it
// in place, without the copy and permutation (and their allocations) a factorisation with
// an ordering makes every time. Every entry of Â gets the list of its terms (value
// indices of G_rk and G_ck, and k), in ascending k, so that assemble_normal_matrix is a
// flat, parallel loop over entries.
void FastProjection::build_normal_pattern(int num_dof) {
  // rows of G touching each column k, with the value index of G_rk
  std::vector<std::vector<std::pair<int, int>>> by_col(num_dof);
  const int* outer = m_G.outerIndexPtr();
  const int* inner = m_G.innerIndexPtr();
  for (int r = 0; r < m_rows; ++r)
    for (int p = outer[r]; p < outer[r + 1]; ++p) by_col[inner[p]].emplace_back(r, p);
  struct Term {
    int col, row, k, ga, gb;
  };
  std::vector<Term> terms;
  for (int k = 0; k < num_dof; ++k)
    for (const auto& [r, pr] : by_col[k])
      for (const auto& [c, pc] : by_col[k])
        if (r >= c) terms.push_back({c, r, k, pr, pc});
  // the ordering, from the symmetric pattern (every row has a diagonal term)
  {
    std::vector<Eigen::Triplet<int>> structure;
    for (const Term& t : terms) {
      structure.emplace_back(t.row, t.col, 1);
      structure.emplace_back(t.col, t.row, 1);
    }
    Eigen::SparseMatrix<int> pattern(m_rows, m_rows);
    pattern.setFromTriplets(structure.begin(), structure.end());
    Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> pinv;
    Eigen::AMDOrdering<int>()(pattern, pinv);
    // as SimplicialCholeskyBase::ordering: P = Pinv⁻¹, row r of A is row P(r) of Â
    m_perm.resize(m_rows);
    if (pinv.size() == m_rows) {
      const Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> perm = pinv.inverse();
      for (int r = 0; r < m_rows; ++r) m_perm[r] = perm.indices()[r];
    } else {
      for (int r = 0; r < m_rows; ++r) m_perm[r] = r;
    }
  }
  // permuted upper triangle: (row, col) ← (min, max) of the permuted indices
  for (Term& t : terms) {
    const int pr = m_perm[t.row], pc = m_perm[t.col];
    t.row = std::min(pr, pc);
    t.col = std::max(pr, pc);
  }
  std::sort(terms.begin(), terms.end(), [](const Term& a, const Term& b) {
    return std::tie(a.col, a.row, a.k) < std::tie(b.col, b.row, b.k);
  });
  std::vector<Eigen::Triplet<double>> entries;
  for (size_t t = 0; t < terms.size(); ++t)
    if (t == 0 || terms[t].col != terms[t - 1].col || terms[t].row != terms[t - 1].row)
      entries.emplace_back(terms[t].row, terms[t].col, 0.0);
  m_A.resize(m_rows, m_rows);
  m_A.setFromTriplets(entries.begin(), entries.end());
  m_A.makeCompressed();
  // terms are sorted like the compressed (column-major) entries: number them in order
  m_term_begin.assign(m_A.nonZeros() + 1, 0);
  m_terms.clear();
  m_terms.reserve(terms.size());
  Eigen::Index e = -1;
  for (size_t t = 0; t < terms.size(); ++t) {
    if (t == 0 || terms[t].col != terms[t - 1].col || terms[t].row != terms[t - 1].row) {
      ++e;
      m_term_begin[e] = static_cast<int>(m_terms.size());
    }
    m_terms.push_back({terms[t].ga, terms[t].gb, terms[t].k});
  }
  m_term_begin[m_A.nonZeros()] = static_cast<int>(m_terms.size());
  assert(e + 1 == m_A.nonZeros());
  m_diag.resize(m_rows);
  for (int c = 0; c < m_rows; ++c) {
    // the diagonal is the last (largest-row) entry of its upper column
    m_diag[c] = m_A.outerIndexPtr()[c + 1] - 1;
    assert(m_A.innerIndexPtr()[m_diag[c]] == c);
  }
  m_cperm.resize(m_rows);
  m_xperm.resize(m_rows);
  m_dlambda.resize(m_rows);
}

void FastProjection::assemble_normal_matrix(const Model& model) {
  const double* g = m_G.valuePtr();
  const double* inv_m = model.inv_mass3.data();
  double* a = m_A.valuePtr();
  const Eigen::Index nnz = m_A.nonZeros();
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, nnz, 1024), [&](const auto& range) {
    for (Eigen::Index e = range.begin(); e < range.end(); ++e) {
      double sum = 0;
      for (int t = m_term_begin[e]; t < m_term_begin[e + 1]; ++t) {
        const NormalTerm& term = m_terms[t];
        sum += g[term.ga] * inv_m[term.k] * g[term.gb];
      }
      a[e] = sum;
    }
  });
  // a relative ridge of 1e-12 keeps redundant constraint sets (e.g. a yarn pinned at
  // both ends with every length held) factorisable without changing the solution
  double max_diag = 0;
  for (int c = 0; c < m_rows; ++c) max_diag = std::max(max_diag, std::abs(a[m_diag[c]]));
  const double ridge = 1e-12 * max_diag;
  for (int c = 0; c < m_rows; ++c) a[m_diag[c]] += ridge;
}

void FastProjection::evaluate(const Model& model, const Eigen::VectorXd& q, double time,
                              Eigen::VectorXd& c) {
  evaluate_impl(model, q, time, c, false);
}

// C(q); with `jacobian`, the values of the rows of G whose gradient varies, at q too, from
// the same group call (the other rows are constant). A group's rows are contiguous in the
// row-major G, so its values are too.
void FastProjection::evaluate_impl(const Model& model, const Eigen::VectorXd& q, double time,
                                   Eigen::VectorXd& c, bool jacobian) {
  c.resize(m_rows);
  double* values = m_G.valuePtr();
  const int* outer = m_G.outerIndexPtr();
  for (size_t g = 0; g < model.constraint_groups.size(); ++g) {
    const ConstraintGroup& group = *model.constraint_groups[g];
    const int row0 = m_group_row[g];
    double* jac = jacobian && group.jacobian_varies() ? values + outer[row0] : nullptr;
    group.evaluate(model, q, time, c.data() + row0, jac);
  }
}

double FastProjection::max_violation(const Model& model, const Eigen::VectorXd& q, double time) {
  evaluate(model, q, time, m_c);
  return m_rows ? max_abs(m_c) : 0.0;
}

void FastProjection::record_groups(const Model& model, const Eigen::VectorXd& q, double time,
                                   double h, std::vector<ConstraintRecord>& records) const {
  records.resize(model.constraint_groups.size());
  const double* values = m_G.valuePtr();
  const int* outer = m_G.outerIndexPtr();
  const int* inner = m_G.innerIndexPtr();
  const double inv_h2 = 1.0 / (h * h);
  for (size_t g = 0; g < model.constraint_groups.size(); ++g) {
    const ConstraintGroup& group = *model.constraint_groups[g];
    ConstraintRecord& rec = records[g];
    const int r0 = m_group_row[g], r1 = m_group_row[g + 1];
    rec.name = group.name();
    rec.kind = std::string(group.kind());
    rec.rows = r1 - r0;
    rec.multipliers = m_lambda.segment(r0, r1 - r0);
    rec.max_violation = r1 > r0 ? max_abs(m_c.segment(r0, r1 - r0)) : 0.0;
    rec.about = group.torque_point(model, q, time);
    rec.force.setZero();
    rec.torque.setZero();
    if (!group.exerts_net_force()) continue;
    // F_k = −Σ_r G_rk Λ_r / h², entry by entry
    for (int r = r0; r < r1; ++r)
      for (int p = outer[r]; p < outer[r + 1]; ++p) {
        const int dof = inner[p];
        Eigen::Vector3d f = Eigen::Vector3d::Zero();
        f[dof % 3] = -values[p] * m_lambda[r] * inv_h2;
        rec.force += f;
        rec.torque += (q.segment<3>(dof - dof % 3) - rec.about).cross(f);
      }
    group.finish_record(rec, h);
  }
}

double FastProjection::max_length_violation(const Model& model, const Eigen::VectorXd& q) {
  std::vector<double> c(model.num_seg());
  length_constraints(model, q, {}, model.num_seg(), c.data(), nullptr);
  double worst = 0;
  for (double value : c) worst = std::max(worst, std::abs(value));
  return worst;
}

ProjectionResult FastProjection::project(const Model& model, Eigen::VectorXd& q, double time,
                                         bool at_least_once) {
  ProjectionResult res;
  m_lambda.setZero(m_rows);
  if (m_rows == 0) return res;
  const double tol = model.params.solver.constraint_tolerance;
  // C and G at the current q in one pass; the last pass's G goes unused
  evaluate_impl(model, q, time, m_c, true);
  res.max_violation = max_abs(m_c);
  while (res.max_violation > tol || (at_least_once && res.iterations == 0)) {
    if (res.iterations >= model.params.solver.max_projection_iterations ||
        !std::isfinite(res.max_violation)) {
      res.converged = false;
      return res;
    }
    // Â = P G M⁻¹ Gᵀ Pᵀ (upper triangle) into its fixed pattern; the symbolic
    // factorisation is computed once
    assemble_normal_matrix(model);
    if (!m_analyzed) {
      m_solver.analyzePattern(m_A);
      m_analyzed = true;
    }
    m_solver.factorize(m_A);
    if (m_solver.info() != Eigen::Success) {
      res.converged = false;
      return res;
    }
    // Â x̂ = P C, δλ = Pᵀ x̂
    for (int r = 0; r < m_rows; ++r) m_cperm[m_perm[r]] = m_c[r];
    m_xperm = m_solver.solve(m_cperm);
    for (int r = 0; r < m_rows; ++r) m_dlambda[r] = m_xperm[m_perm[r]];
    m_lambda += m_dlambda;
    q.noalias() -= model.inv_mass3.cwiseProduct(m_G.transpose() * m_dlambda);
    ++res.iterations;
    evaluate_impl(model, q, time, m_c, true);
    res.max_violation = max_abs(m_c);
  }
  return res;
}

}  // namespace knit
