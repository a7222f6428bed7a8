#include "knit/sheet/bw_energy.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "knit/sheet/jet.hpp"

namespace knit::sheet {

namespace {

using Eigen::Vector3d;

// weights of the vertices in w_u = Σ αᵢ xᵢ and w_v = Σ βᵢ xᵢ
void direction_weights(const Eigen::Matrix2d& dinv, Vector3d& alpha, Vector3d& beta) {
  alpha = Vector3d(-dinv(0, 0) - dinv(1, 0), dinv(0, 0), dinv(1, 0));
  beta = Vector3d(-dinv(0, 1) - dinv(1, 1), dinv(0, 1), dinv(1, 1));
}

// C = √a (‖w‖ − 1) for w = Σ wtᵢ xᵢ
Condition<9> stretch_one(const Vector3d& w, const Vector3d& wt, double area, bool hessian) {
  Condition<9> c;
  c.curvature_psd = true;
  const double s = std::sqrt(area), len = w.norm();
  c.c = s * (len - 1);
  if (!(len > 0)) return c;  // degenerate: zero gradient
  const Vector3d n = w / len;
  for (int i = 0; i < 3; ++i) c.grad.segment<3>(3 * i) = s * wt[i] * n;
  if (hessian) {
    const Eigen::Matrix3d p = (Eigen::Matrix3d::Identity() - n * n.transpose()) / len;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) c.hess.block<3, 3>(3 * i, 3 * j) = s * wt[i] * wt[j] * p;
  }
  return c;
}

template <class T>
struct V3 {
  T x, y, z;
};
template <class T>
V3<T> sub(const V3<T>& a, const V3<T>& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
template <class T>
V3<T> cross(const V3<T>& a, const V3<T>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <class T>
T dot(const V3<T>& a, const V3<T>& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}

// the value of a number or of a Jet
double value_of(double x) {
  return x;
}
template <int N>
double value_of(const detail::Jet<N>& x) {
  return x.v;
}

double wrap_angle(double a);

// θ = atan2((n1 × n2)·e, ‖e‖ n1·n2) on 4 stacked points (x1, x2, x3, x4); with rest_product
// > 0 the bend condition C_b = (‖n1‖ ‖n2‖ / rest_product) wrap(θ − rest_angle) instead
template <class T>
T bend_angle_t(const V3<T> p[4], double rest_angle = 0, double rest_product = 0) {
  using detail::atan2;
  using detail::sqrt;
  using std::atan2;
  using std::sqrt;
  const V3<T> n1 = cross(sub(p[0], p[2]), sub(p[0], p[3]));
  const V3<T> n2 = cross(sub(p[1], p[3]), sub(p[1], p[2]));
  const V3<T> e = sub(p[3], p[2]);
  const T y = dot(cross(n1, n2), e);
  const T x = sqrt(dot(e, e)) * dot(n1, n2);
  const T theta = atan2(y, x);
  if (!(rest_product > 0)) return theta;
  const double t = value_of(theta);
  // θ − θ₀ wrapped into (−π, π]: θ plus a constant
  const T phi = theta + (wrap_angle(t - rest_angle) - t);
  return (1 / rest_product) * (sqrt(dot(n1, n1) * dot(n2, n2)) * phi);
}

// wraps an angle difference into (−π, π]
double wrap_angle(double a) {
  constexpr double pi = std::numbers::pi;
  a = std::remainder(a, 2 * pi);
  return a == -pi ? pi : a;
}

void check_size(const Eigen::VectorXd& x, int n, const char* what) {
  if (x.size() != 3 * n)
    throw std::invalid_argument(std::string("sheet forces: ") + what + " has " +
                                std::to_string(x.size()) + " entries, expected 3 per node (" +
                                std::to_string(3 * n) + ")");
}

// adds a local N×N block into a matrix with the mesh's cached pattern, at the element's slots
template <int N>
void add_block(const Eigen::Matrix<double, N, N>& m, const int* nodes, const int* slots,
               Eigen::SparseMatrix<double>& out) {
  constexpr int n = N / 3;
  double* values = out.valuePtr();
  const int* outer = out.outerIndexPtr();
  for (int b = 0; b < n; ++b)
    for (int c = 0; c < 3; ++c)
      for (int a = 0; a < n; ++a) {
        double* v = values + outer[3 * nodes[b] + c] + slots[n * a + b];
        for (int r = 0; r < 3; ++r) v[r] += m(3 * a + r, 3 * b + c);
      }
}

// the nearest PSD matrix to a symmetric element Hessian: its negative eigenvalues set to 0
template <int N>
void project_psd(Eigen::Matrix<double, N, N>& h) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> eig(h);
  const Eigen::Matrix<double, N, 1> lambda = eig.eigenvalues().cwiseMax(0.0);
  h = eig.eigenvectors() * lambda.asDiagonal() * eig.eigenvectors().transpose();
}

// scatters a local N×N block into triplets
template <int N>
void scatter(const Eigen::Matrix<double, N, N>& m, const int* nodes,
             std::vector<Eigen::Triplet<double>>& out) {
  for (int a = 0; a < N / 3; ++a)
    for (int b = 0; b < N / 3; ++b)
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
          out.emplace_back(3 * nodes[a] + r, 3 * nodes[b] + c, m(3 * a + r, 3 * b + c));
}

}  // namespace

Vector9d triangle_positions(const std::array<int, 3>& tri, const Eigen::VectorXd& x) {
  Vector9d p;
  for (int k = 0; k < 3; ++k) p.segment<3>(3 * k) = x.segment<3>(3 * tri[k]);
  return p;
}

Vector12d hinge_positions(const SheetHinge& h, const Eigen::VectorXd& x) {
  Vector12d p;
  p.segment<3>(0) = x.segment<3>(3 * h.opposite[0]);
  p.segment<3>(3) = x.segment<3>(3 * h.opposite[1]);
  p.segment<3>(6) = x.segment<3>(3 * h.edge[0]);
  p.segment<3>(9) = x.segment<3>(3 * h.edge[1]);
  return p;
}

std::array<Vector3d, 2> deformation_gradient(const Vector9d& x, const Eigen::Matrix2d& dinv) {
  const Vector3d d1 = x.segment<3>(3) - x.segment<3>(0), d2 = x.segment<3>(6) - x.segment<3>(0);
  return {d1 * dinv(0, 0) + d2 * dinv(1, 0), d1 * dinv(0, 1) + d2 * dinv(1, 1)};
}

std::array<Condition<9>, 2> stretch_conditions(const Vector9d& x, const Eigen::Matrix2d& dinv,
                                               double area, bool hessian) {
  Vector3d alpha, beta;
  direction_weights(dinv, alpha, beta);
  const auto w = deformation_gradient(x, dinv);
  return {stretch_one(w[0], alpha, area, hessian), stretch_one(w[1], beta, area, hessian)};
}

Condition<9> shear_condition(const Vector9d& x, const Eigen::Matrix2d& dinv, double area,
                             bool hessian) {
  Vector3d alpha, beta;
  direction_weights(dinv, alpha, beta);
  const auto w = deformation_gradient(x, dinv);
  const double s = std::sqrt(area);
  Condition<9> c;
  c.c = s * w[0].dot(w[1]);
  for (int i = 0; i < 3; ++i) c.grad.segment<3>(3 * i) = s * (alpha[i] * w[1] + beta[i] * w[0]);
  if (hessian)
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        c.hess.block<3, 3>(3 * i, 3 * j) =
            s * (alpha[i] * beta[j] + beta[i] * alpha[j]) * Eigen::Matrix3d::Identity();
  return c;
}

double bend_angle(const Vector12d& x) {
  V3<double> p[4];
  for (int k = 0; k < 4; ++k) p[k] = {x[3 * k], x[3 * k + 1], x[3 * k + 2]};
  return bend_angle_t(p);
}

double bend_area_product(const Vector12d& x) {
  const Vector3d x1 = x.segment<3>(0), x2 = x.segment<3>(3), x3 = x.segment<3>(6),
                 x4 = x.segment<3>(9);
  return (x1 - x3).cross(x1 - x4).norm() * (x2 - x4).cross(x2 - x3).norm();
}

Condition<12> bend_condition(const Vector12d& x, double rest_angle, double rest_product,
                             bool hessian) {
  if (!(rest_product > 0) || !std::isfinite(rest_product))
    throw std::invalid_argument("bend_condition: the rest area product must be positive, got " +
                                std::to_string(rest_product));
  Condition<12> c;
  const Vector3d x1 = x.segment<3>(0), x2 = x.segment<3>(3), x3 = x.segment<3>(6),
                 x4 = x.segment<3>(9);
  const Vector3d n1 = (x1 - x3).cross(x1 - x4), n2 = (x2 - x4).cross(x2 - x3);
  const Vector3d e = x4 - x3;
  const double le = e.norm(), a1 = n1.squaredNorm(), a2 = n2.squaredNorm();
  // degenerate (a collapsed triangle): the weight, and so C_b and its gradient, are zero
  if (!(le > 0) || !(a1 > 0) || !(a2 > 0)) return c;
  const double phi = wrap_angle(std::atan2(n1.cross(n2).dot(e), le * n1.dot(n2)) - rest_angle);
  const double l1 = std::sqrt(a1), l2 = std::sqrt(a2), w = l1 * l2 / rest_product;
  c.c = w * phi;
  // ∂θ/∂x (header comment)
  const Vector3d eh = e / le, m1 = n1 / a1, m2 = n2 / a2;
  Vector12d dtheta;
  dtheta.segment<3>(0) = -le * m1;
  dtheta.segment<3>(3) = -le * m2;
  dtheta.segment<3>(6) = -((x1 - x4).dot(eh) * m1 + (x2 - x4).dot(eh) * m2);
  dtheta.segment<3>(9) = (x1 - x3).dot(eh) * m1 + (x2 - x3).dot(eh) * m2;
  // ∂w/∂x from the gradients of the normals' lengths: for a triangle (a, b, c) with
  // n = (b − a) × (c − a), ∂‖n‖/∂a = n̂ × (c − b), ∂‖n‖/∂b = n̂ × (a − c), ∂‖n‖/∂c = n̂ × (b − a)
  const Vector3d u1 = n1 / l1, u2 = n2 / l2;  // triangles (x1, x3, x4) and (x2, x4, x3)
  Vector12d dw;
  dw.segment<3>(0) = l2 * u1.cross(x4 - x3);
  dw.segment<3>(3) = l1 * u2.cross(x3 - x4);
  dw.segment<3>(6) = l2 * u1.cross(x1 - x4) + l1 * u2.cross(x4 - x2);
  dw.segment<3>(9) = l2 * u1.cross(x3 - x1) + l1 * u2.cross(x2 - x3);
  c.grad = w * dtheta + (phi / rest_product) * dw;
  if (hessian) {
    using J = detail::Jet<12>;
    V3<J> p[4];
    for (int k = 0; k < 4; ++k)
      p[k] = {J::variable(x[3 * k], 3 * k), J::variable(x[3 * k + 1], 3 * k + 1),
              J::variable(x[3 * k + 2], 3 * k + 2)};
    c.hess = bend_angle_t(p, rest_angle, rest_product).h;
  }
  return c;
}

double stretch_energy(const Vector9d& x, const Eigen::Matrix2d& dinv, double area, double k_u,
                      double k_v, Vector9d* grad, Matrix9d* hess, HessianKind kind) {
  const auto cs = stretch_conditions(x, dinv, area, hess != nullptr);
  return condition_energy(cs[0], k_u, grad, hess, kind) +
         condition_energy(cs[1], k_v, grad, hess, kind);
}

double shear_energy(const Vector9d& x, const Eigen::Matrix2d& dinv, double area, double k,
                    Vector9d* grad, Matrix9d* hess, HessianKind kind) {
  return condition_energy(shear_condition(x, dinv, area, hess != nullptr), k, grad, hess, kind);
}

double bend_energy(const Vector12d& x, double rest_angle, double rest_product, double k,
                   Vector12d* grad, Matrix12d* hess, HessianKind kind) {
  const bool need_curvature = hess != nullptr && kind == HessianKind::EXACT;
  return condition_energy(bend_condition(x, rest_angle, rest_product, need_curvature), k, grad,
                          hess, kind);
}

SheetForces evaluate_forces(const SheetMesh& mesh, const SheetMaterial& material,
                            const Eigen::VectorXd& x, const Eigen::VectorXd& v,
                            const Eigen::Vector3d& gravity, Jacobians jacobians) {
  SheetForces out;
  evaluate_forces(mesh, material, x, v, gravity, jacobians, out);
  return out;
}

void evaluate_forces(const SheetMesh& mesh, const SheetMaterial& material, const Eigen::VectorXd& x,
                     const Eigen::VectorXd& v, const Eigen::Vector3d& gravity, Jacobians jacobians,
                     SheetForces& out) {
  const int n = mesh.num_nodes();
  check_size(x, n, "positions");
  check_size(v, n, "velocities");
  const bool jac = jacobians != Jacobians::NONE;
  const bool project = jacobians == Jacobians::PROJECTED;
  const HessianKind kind = jacobians == Jacobians::PSD ? HessianKind::PSD : HessianKind::EXACT;
  // the bending condition's curvature is needed only for the exact Hessian (and its
  // projection); the stretch and shear ones are cheap, and the PSD stretch Hessian uses its
  // curvature
  const bool bend_curvature = kind == HessianKind::EXACT;

  out.elastic_energy = out.stretch_energy = out.shear_energy = out.bend_energy = 0;
  out.gravity_energy = 0;
  out.force.setZero(3 * n);
  // with the mesh's cached pattern the blocks go straight into the matrices' values
  const bool cached = mesh.jacobian_pattern.rows() == 3 * n &&
                      mesh.jacobian_pattern.isCompressed() &&
                      mesh.triangle_slots.size() == mesh.triangles.size() &&
                      mesh.hinge_slots.size() == mesh.hinges.size();
  std::vector<Eigen::Triplet<double>> kt, dt;
  if (jac && cached) {
    // the matrices of an earlier evaluation on this mesh keep their storage: zeroed, not
    // copied (a solver's loop then allocates nothing)
    for (Eigen::SparseMatrix<double>* m : {&out.dfdx, &out.dfdv}) {
      if (m->rows() == 3 * n && m->isCompressed() &&
          m->nonZeros() == mesh.jacobian_pattern.nonZeros() &&
          std::equal(m->innerIndexPtr(), m->innerIndexPtr() + m->nonZeros(),
                     mesh.jacobian_pattern.innerIndexPtr()) &&
          std::equal(m->outerIndexPtr(), m->outerIndexPtr() + m->outerSize() + 1,
                     mesh.jacobian_pattern.outerIndexPtr()))
        std::fill(m->valuePtr(), m->valuePtr() + m->nonZeros(), 0.0);
      else
        *m = mesh.jacobian_pattern;
    }
  } else if (!jac) {
    out.dfdx.resize(0, 0);  // none asked for: none left from an earlier evaluation
    out.dfdv.resize(0, 0);
  } else {
    kt.reserve(81 * mesh.triangles.size() + 144 * mesh.hinges.size());
    dt.reserve(kt.capacity());
  }

  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    const Vector9d xt = triangle_positions(tri, x), vt = triangle_positions(tri, v);
    const auto st = stretch_conditions(xt, mesh.dinv[t], mesh.area[t], jac);
    const Condition<9> sh = shear_condition(xt, mesh.dinv[t], mesh.area[t], jac);
    Vector9d g = Vector9d::Zero(), f = Vector9d::Zero();
    Matrix9d h = Matrix9d::Zero(), dv = Matrix9d::Zero();
    Matrix9d* hp = jac ? &h : nullptr;
    Matrix9d* dvp = jac ? &dv : nullptr;
    for (int d = 0; d < 2; ++d) {
      const double k = d == 0 ? material.k_stretch_u : material.k_stretch_v;
      out.stretch_energy += condition_energy(st[d], k, &g, hp, kind);
      condition_damping(st[d], vt, material.d_stretch, &f, dvp);
    }
    out.shear_energy += condition_energy(sh, material.k_shear, &g, hp, kind);
    condition_damping(sh, vt, material.d_shear, &f, dvp);
    f -= g;
    if (jac && project) project_psd(h);
    for (int k = 0; k < 3; ++k) out.force.segment<3>(3 * tri[k]) += f.segment<3>(3 * k);
    if (jac && cached) {
      add_block<9>(-h, tri.data(), mesh.triangle_slots[t].data(), out.dfdx);
      add_block<9>(dv, tri.data(), mesh.triangle_slots[t].data(), out.dfdv);
    } else if (jac) {
      scatter<9>(-h, tri.data(), kt);
      scatter<9>(dv, tri.data(), dt);
    }
  }

  for (size_t e = 0; e < mesh.hinges.size(); ++e) {
    const SheetHinge& hg = mesh.hinges[e];
    const int nodes[4] = {hg.opposite[0], hg.opposite[1], hg.edge[0], hg.edge[1]};
    const Vector12d xh = hinge_positions(hg, x), vh = hinge_positions(hg, v);
    const Condition<12> c =
        bend_condition(xh, hg.rest_angle, hg.rest_area_product, jac && bend_curvature);
    Vector12d g = Vector12d::Zero(), f = Vector12d::Zero();
    Matrix12d h = Matrix12d::Zero(), dv = Matrix12d::Zero();
    out.bend_energy += condition_energy(c, material.k_bend, &g, jac ? &h : nullptr, kind);
    condition_damping(c, vh, material.d_bend, &f, jac ? &dv : nullptr);
    f -= g;
    if (jac && project) project_psd(h);
    for (int k = 0; k < 4; ++k) out.force.segment<3>(3 * nodes[k]) += f.segment<3>(3 * k);
    if (jac && cached) {
      add_block<12>(-h, nodes, mesh.hinge_slots[e].data(), out.dfdx);
      add_block<12>(dv, nodes, mesh.hinge_slots[e].data(), out.dfdv);
    } else if (jac) {
      scatter<12>(-h, nodes, kt);
      scatter<12>(dv, nodes, dt);
    }
  }

  for (int i = 0; i < n; ++i) {
    out.force.segment<3>(3 * i) += mesh.mass[i] * gravity;
    out.gravity_energy -= mesh.mass[i] * gravity.dot(x.segment<3>(3 * i));
  }
  out.elastic_energy = out.stretch_energy + out.shear_energy + out.bend_energy;
  if (jac && !cached) {
    out.dfdx.resize(3 * n, 3 * n);
    out.dfdx.setFromTriplets(kt.begin(), kt.end());
    out.dfdv.resize(3 * n, 3 * n);
    out.dfdv.setFromTriplets(dt.begin(), dt.end());
  }
}

double potential_energy(const SheetMesh& mesh, const SheetMaterial& material,
                        const Eigen::VectorXd& x, const Eigen::Vector3d& gravity) {
  const int n = mesh.num_nodes();
  check_size(x, n, "positions");
  double e = 0;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Vector9d xt = triangle_positions(mesh.triangles[t], x);
    const auto st = stretch_conditions(xt, mesh.dinv[t], mesh.area[t], false);
    e +=
        0.5 * (material.k_stretch_u * st[0].c * st[0].c + material.k_stretch_v * st[1].c * st[1].c);
    const double s = shear_condition(xt, mesh.dinv[t], mesh.area[t], false).c;
    e += 0.5 * material.k_shear * s * s;
  }
  for (const SheetHinge& hg : mesh.hinges) {
    const double c =
        bend_condition(hinge_positions(hg, x), hg.rest_angle, hg.rest_area_product, false).c;
    e += 0.5 * material.k_bend * c * c;
  }
  for (int i = 0; i < n; ++i) e -= mesh.mass[i] * gravity.dot(x.segment<3>(3 * i));
  return e;
}

}  // namespace knit::sheet
