#include "knit/constraints/projection.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "knit/constraints/inextensibility.hpp"

namespace knit {

FastProjection::FastProjection(const Model& model) {
  m_len_rows = model.params.length_constraints ? model.num_seg() : 0;
  m_rows = m_len_rows + 3 * static_cast<int>(model.pins.size() + model.glues.size());
  std::vector<Eigen::Triplet<double>> trip;
  // inextensibility rows: structure only, values filled by update_jacobian
  for (int i = 0; i < m_len_rows; ++i)
    for (int k = 0; k < 12; ++k) trip.emplace_back(i, 3 * model.seg_cp[i] + k, 1.0);
  int row = m_len_rows;
  auto add_point = [&](int r, const YarnPoint& p, double sign) {
    const Eigen::Vector4d b = bspline_basis(p.t);
    for (int a = 0; a < 4; ++a)
      for (int c = 0; c < 3; ++c)
        trip.emplace_back(r + c, 3 * (model.seg_cp[p.segment] + a) + c, sign * b[a]);
  };
  for (const Pin& pin : model.pins) {
    add_point(row, pin.at, 1.0);
    row += 3;
  }
  for (const Glue& glue : model.glues) {
    add_point(row, glue.a, 1.0);
    add_point(row, glue.b, -1.0);  // duplicates (shared control points) are summed
    row += 3;
  }
  m_G.resize(m_rows, model.num_dof());
  m_G.setFromTriplets(trip.begin(), trip.end());
  m_G.makeCompressed();
}

void FastProjection::update_jacobian(const Model& model, const Eigen::VectorXd& q) {
  double* values = m_G.valuePtr();
  const int* outer = m_G.outerIndexPtr();
  tbb::parallel_for(tbb::blocked_range<int>(0, m_len_rows, 256), [&](const auto& r) {
    Vector12d g;
    for (int i = r.begin(); i < r.end(); ++i) {
      length_constraint(gather_segment(q, model.seg_cp[i]), model.rest_length[i], model.quad, &g);
      // row i holds its 12 columns 3·cp … 3·cp+11 in ascending order
      for (int k = 0; k < 12; ++k) values[outer[i] + k] = g[k];
    }
  });
}

void FastProjection::evaluate(const Model& model, const Eigen::VectorXd& q, double time,
                              Eigen::VectorXd& c) {
  c.resize(m_rows);
  tbb::parallel_for(tbb::blocked_range<int>(0, m_len_rows, 256), [&](const auto& r) {
    for (int i = r.begin(); i < r.end(); ++i)
      c[i] = length_constraint(gather_segment(q, model.seg_cp[i]), model.rest_length[i],
                               model.quad, nullptr);
  });
  int row = m_len_rows;
  for (const Pin& pin : model.pins) {
    c.segment<3>(row) = point_position(model, q, pin.at) - pin.target(time);
    row += 3;
  }
  for (const Glue& glue : model.glues) {
    c.segment<3>(row) = point_position(model, q, glue.a) - point_position(model, q, glue.b) - glue.offset(time);
    row += 3;
  }
}

double FastProjection::max_violation(const Model& model, const Eigen::VectorXd& q, double time) {
  evaluate(model, q, time, m_c);
  return m_rows ? m_c.cwiseAbs().maxCoeff() : 0.0;
}

double FastProjection::max_length_violation(const Model& model, const Eigen::VectorXd& q) {
  double worst = 0;
  for (int i = 0; i < model.num_seg(); ++i)
    worst = std::max(worst, std::abs(length_constraint(gather_segment(q, model.seg_cp[i]),
                                                       model.rest_length[i], model.quad,
                                                       nullptr)));
  return worst;
}

ProjectionResult FastProjection::project(const Model& model, Eigen::VectorXd& q, double time) {
  ProjectionResult res;
  if (m_rows == 0) return res;
  const double tol = model.params.constraint_tolerance;
  evaluate(model, q, time, m_c);
  res.max_violation = m_c.cwiseAbs().maxCoeff();
  while (res.max_violation > tol) {
    if (res.iterations >= model.params.max_projection_iterations || !std::isfinite(res.max_violation)) {
      res.converged = false;
      return res;
    }
    update_jacobian(model, q);
    m_A = m_G * model.inv_mass3.asDiagonal() * m_G.transpose();
    // a relative ridge of 1e-12 keeps redundant constraint sets (e.g. a yarn pinned at
    // both ends with every length held) factorisable without changing the solution
    const double ridge = 1e-12 * m_A.diagonal().cwiseAbs().maxCoeff();
    for (int k = 0; k < m_rows; ++k) m_A.coeffRef(k, k) += ridge;
    if (m_A.nonZeros() != m_pattern_nnz) {
      m_solver.analyzePattern(m_A);
      m_pattern_nnz = m_A.nonZeros();
    }
    m_solver.factorize(m_A);
    if (m_solver.info() != Eigen::Success) {
      res.converged = false;
      return res;
    }
    m_dlambda = m_solver.solve(m_c);
    q.noalias() -= model.inv_mass3.cwiseProduct(m_G.transpose() * m_dlambda);
    ++res.iterations;
    evaluate(model, q, time, m_c);
    res.max_violation = m_c.cwiseAbs().maxCoeff();
  }
  return res;
}

}  // namespace knit
