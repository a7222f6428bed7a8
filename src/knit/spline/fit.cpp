#include "knit/spline/fit.hpp"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "knit/spline/basis.hpp"

namespace knit {

Eigen::Matrix3Xd fit_bspline(const Eigen::Matrix3Xd& samples, const Eigen::VectorXd& u,
                             int segments, const Eigen::Matrix3Xd& fixed, double smoothing) {
  if (segments < 1) throw std::invalid_argument("fit_bspline: need at least one segment");
  if (samples.cols() != u.size())
    throw std::invalid_argument("fit_bspline: samples and parameters differ in count");
  const int m = segments + 3;
  const int nfix = static_cast<int>(fixed.cols());
  if (nfix > m) throw std::invalid_argument("fit_bspline: more fixed points than control points");
  const int nfree = m - nfix;
  if (nfree == 0) return fixed;
  // normal equations (AᵀA + λ DᵀD) x = Aᵀb − (coupling to fixed points), per coordinate
  std::vector<Eigen::Triplet<double>> trip;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(nfree, 3);
  auto add_row = [&](const int* idx, const double* w, int count, const Eigen::Vector3d& b,
                     double weight) {
    for (int a = 0; a < count; ++a) {
      const int ia = idx[a] - nfix;
      if (ia < 0) continue;
      Eigen::Vector3d r = weight * w[a] * b;
      for (int c = 0; c < count; ++c) {
        const int ic = idx[c] - nfix;
        if (ic < 0)
          r -= weight * w[a] * w[c] * fixed.col(idx[c]);
        else
          trip.emplace_back(ia, ic, weight * w[a] * w[c]);
      }
      rhs.row(ia) += r.transpose();
    }
  };
  for (int j = 0; j < samples.cols(); ++j) {
    const double uj = std::clamp(u[j], 0.0, static_cast<double>(segments));
    const int seg = std::min(static_cast<int>(std::floor(uj)), segments - 1);
    const Eigen::Vector4d b = bspline_basis(uj - seg);
    const int idx[4] = {seg, seg + 1, seg + 2, seg + 3};
    add_row(idx, b.data(), 4, samples.col(j), 1.0);
  }
  const double lambda = smoothing * std::max<double>(1.0, static_cast<double>(samples.cols()) / m);
  for (int k = 0; k + 2 < m; ++k) {
    const int idx[3] = {k, k + 1, k + 2};
    const double w[3] = {1.0, -2.0, 1.0};
    add_row(idx, w, 3, Eigen::Vector3d::Zero(), lambda);
  }
  // a tiny ridge keeps the system definite even with no samples near some control point
  for (int k = 0; k < nfree; ++k) trip.emplace_back(k, k, 1e-12);
  Eigen::SparseMatrix<double> A(nfree, nfree);
  A.setFromTriplets(trip.begin(), trip.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(A);
  if (solver.info() != Eigen::Success) throw std::runtime_error("fit_bspline: singular system");
  const Eigen::MatrixXd x = solver.solve(rhs);
  Eigen::Matrix3Xd cp(3, m);
  if (nfix > 0) cp.leftCols(nfix) = fixed;
  cp.rightCols(nfree) = x.transpose();
  return cp;
}

double polyline_length(const Eigen::Matrix3Xd& p) {
  double len = 0;
  for (int j = 1; j < p.cols(); ++j) len += (p.col(j) - p.col(j - 1)).norm();
  return len;
}

Eigen::Matrix3Xd fit_polyline(const Eigen::Matrix3Xd& polyline, int segments) {
  if (polyline.cols() < 2) throw std::invalid_argument("fit_polyline: need at least 2 points");
  const double total = polyline_length(polyline);
  if (!(total > 0)) throw std::invalid_argument("fit_polyline: polyline has zero length");
  Eigen::VectorXd u(polyline.cols());
  double acc = 0;
  u[0] = 0;
  for (int j = 1; j < polyline.cols(); ++j) {
    acc += (polyline.col(j) - polyline.col(j - 1)).norm();
    u[j] = segments * acc / total;
  }
  // densify so every segment sees several samples
  const int per = 8;
  const int n = segments * per + 1;
  Eigen::Matrix3Xd dense(3, n);
  Eigen::VectorXd du(n);
  int j = 0;
  for (int k = 0; k < n; ++k) {
    const double uk = static_cast<double>(segments) * k / (n - 1);
    while (j + 2 < polyline.cols() && u[j + 1] < uk) ++j;
    const double span = u[j + 1] - u[j];
    const double s = span > 0 ? std::clamp((uk - u[j]) / span, 0.0, 1.0) : 0.0;
    dense.col(k) = (1 - s) * polyline.col(j) + s * polyline.col(j + 1);
    du[k] = uk;
  }
  return fit_bspline(dense, du, segments);
}

Eigen::Matrix3Xd sample_bspline(const Eigen::Matrix3Xd& cp, int per_segment) {
  const int nseg = static_cast<int>(cp.cols()) - 3;
  if (nseg < 1) throw std::invalid_argument("sample_bspline: need at least 4 control points");
  Eigen::Matrix3Xd out(3, nseg * per_segment + 1);
  for (int i = 0; i < nseg; ++i)
    for (int k = 0; k < per_segment; ++k) {
      const Eigen::Vector4d b = bspline_basis(static_cast<double>(k) / per_segment);
      out.col(i * per_segment + k) = cp.middleCols<4>(i) * b;
    }
  out.col(nseg * per_segment) = cp.rightCols<4>() * bspline_basis(1.0);
  return out;
}

}  // namespace knit
