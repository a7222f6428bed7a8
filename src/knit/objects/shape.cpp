#include "knit/objects/shape.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace knit {

namespace {

using Eigen::Vector3d;
constexpr double INF = std::numeric_limits<double>::infinity();

Eigen::AlignedBox3d unbounded() {
  return Eigen::AlignedBox3d(Vector3d::Constant(-INF), Vector3d::Constant(INF));
}

// a unit vector along d, or `fallback` where d vanishes
Vector3d unit_or(const Vector3d& d, const Vector3d& fallback) {
  const double n = d.norm();
  return n > 0 ? Vector3d(d / n) : fallback;
}

class Plane : public Shape {
 public:
  Plane(const Vector3d& p, const Vector3d& n) : m_p(p), m_n(n.normalized()) {}
  std::string_view kind() const override { return "plane"; }
  double distance(const Vector3d& x, Vector3d* grad) const override {
    if (grad) *grad = m_n;
    return m_n.dot(x - m_p);
  }
  Eigen::AlignedBox3d bounds() const override { return unbounded(); }

 private:
  Vector3d m_p, m_n;
};

class Sphere : public Shape {
 public:
  Sphere(const Vector3d& c, double r) : m_c(c), m_r(r) {}
  std::string_view kind() const override { return "sphere"; }
  double distance(const Vector3d& x, Vector3d* grad) const override {
    const Vector3d d = x - m_c;
    if (grad) *grad = unit_or(d, Vector3d::UnitZ());
    return d.norm() - m_r;
  }
  Eigen::AlignedBox3d bounds() const override {
    return Eigen::AlignedBox3d(m_c.array() - m_r, m_c.array() + m_r);
  }

 private:
  Vector3d m_c;
  double m_r;
};

class Box : public Shape {
 public:
  Box(const Vector3d& c, const Vector3d& e) : m_c(c), m_e(e) {}
  std::string_view kind() const override { return "box"; }
  double distance(const Vector3d& x, Vector3d* grad) const override {
    const Vector3d p = x - m_c;
    const Vector3d q = p.cwiseAbs() - m_e;
    const Vector3d out = q.cwiseMax(0.0);
    const double outside = out.norm();
    int axis = 0;
    const double inside = std::min(q.maxCoeff(&axis), 0.0);
    if (grad) {
      if (outside > 0) {
        for (int k = 0; k < 3; ++k) (*grad)[k] = p[k] < 0 ? -out[k] : out[k];
        *grad /= outside;
      } else {
        *grad = Vector3d::Zero();
        (*grad)[axis] = p[axis] < 0 ? -1 : 1;
      }
    }
    return outside + inside;
  }
  Eigen::AlignedBox3d bounds() const override { return Eigen::AlignedBox3d(m_c - m_e, m_c + m_e); }

 private:
  Vector3d m_c, m_e;
};

class Capsule : public Shape {
 public:
  Capsule(const Vector3d& a, const Vector3d& b, double r) : m_a(a), m_b(b), m_r(r) {}
  std::string_view kind() const override { return "capsule"; }
  double distance(const Vector3d& x, Vector3d* grad) const override {
    const Vector3d ab = m_b - m_a;
    const double len2 = ab.squaredNorm();
    const double t = len2 > 0 ? std::clamp((x - m_a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    const Vector3d d = x - (m_a + t * ab);
    if (grad) *grad = unit_or(d, Vector3d::UnitZ());
    return d.norm() - m_r;
  }
  Eigen::AlignedBox3d bounds() const override {
    return Eigen::AlignedBox3d(m_a.cwiseMin(m_b).array() - m_r, m_a.cwiseMax(m_b).array() + m_r);
  }

 private:
  Vector3d m_a, m_b;
  double m_r;
};

class Cylinder : public Shape {
 public:
  Cylinder(const Vector3d& a, const Vector3d& b, double r)
      : m_mid(0.5 * (a + b)),
        m_axis((b - a).normalized()),
        m_half(0.5 * (b - a).norm()),
        m_r(r),
        m_a(a),
        m_b(b) {}
  std::string_view kind() const override { return "cylinder"; }
  double distance(const Vector3d& x, Vector3d* grad) const override {
    const Vector3d p = x - m_mid;
    const double z = p.dot(m_axis);
    const Vector3d radial = p - z * m_axis;
    const double rho = radial.norm();
    const Vector3d e_rho = rho > 0 ? Vector3d(radial / rho) : any_normal();
    const double dr = rho - m_r, dz = std::abs(z) - m_half;
    const Vector3d e_z = z < 0 ? Vector3d(-m_axis) : m_axis;
    double phi;
    Vector3d g;
    if (dr > 0 && dz > 0) {
      phi = std::hypot(dr, dz);
      g = (dr * e_rho + dz * e_z) / phi;
    } else if (dr > dz) {
      phi = dr;
      g = e_rho;
    } else {
      phi = dz;
      g = e_z;
    }
    if (grad) *grad = g;
    return phi;
  }
  Eigen::AlignedBox3d bounds() const override {
    return Eigen::AlignedBox3d(m_a.cwiseMin(m_b).array() - m_r, m_a.cwiseMax(m_b).array() + m_r);
  }

 private:
  Vector3d any_normal() const {
    return unit_or(m_axis.cross(Vector3d::UnitX()), m_axis.cross(Vector3d::UnitY()).normalized());
  }
  Vector3d m_mid, m_axis;
  double m_half, m_r;
  Vector3d m_a, m_b;
};

class Ellipsoid : public Shape {
 public:
  Ellipsoid(const Vector3d& c, const Vector3d& a) : m_c(c), m_a(a) {}
  std::string_view kind() const override { return "ellipsoid"; }
  double distance(const Vector3d& x, Vector3d* grad) const override {
    const Vector3d p = x - m_c;
    const Vector3d u = p.cwiseQuotient(m_a);  // k0 = |u|
    const Vector3d w = u.cwiseQuotient(m_a);  // k1 = |w|
    const double k0 = u.norm(), k1 = w.norm();
    if (!(k1 > 0)) {  // the centre
      if (grad) *grad = Vector3d::UnitZ();
      return -m_a.minCoeff();
    }
    const double phi = k0 * (k0 - 1) / k1;
    if (grad) {
      // ∂k0 = w / k0, ∂k1 = (w / a²) / k1
      const Vector3d dk0 = w / k0;
      const Vector3d dk1 = w.cwiseQuotient(m_a.cwiseProduct(m_a)) / k1;
      *grad = ((2 * k0 - 1) * dk0 * k1 - k0 * (k0 - 1) * dk1) / (k1 * k1);
    }
    return phi;
  }
  Eigen::AlignedBox3d bounds() const override { return Eigen::AlignedBox3d(m_c - m_a, m_c + m_a); }
  double lipschitz() const override {
    const double ratio = m_a.maxCoeff() / m_a.minCoeff();
    return ratio * ratio;
  }

 private:
  Vector3d m_c, m_a;
};

class Union : public Shape {
 public:
  Union(std::vector<ShapePtr> members, double blend) : m_members(std::move(members)), m_k(blend) {}
  std::string_view kind() const override { return m_k > 0 ? "smooth_union" : "union"; }
  double distance(const Vector3d& x, Vector3d* grad) const override {
    Vector3d g_acc, g;
    double phi = m_members[0]->distance(x, grad ? &g_acc : nullptr);
    for (size_t k = 1; k < m_members.size(); ++k) {
      const double b = m_members[k]->distance(x, grad ? &g : nullptr);
      if (m_k > 0) {
        double h = 0;
        phi = smooth_min(phi, b, m_k, h);
        if (grad) g_acc = h * g_acc + (1 - h) * g;
      } else if (b < phi) {
        phi = b;
        if (grad) g_acc = g;
      }
    }
    if (grad) *grad = g_acc;
    return phi;
  }
  Eigen::AlignedBox3d bounds() const override {
    Eigen::AlignedBox3d box;
    for (const ShapePtr& m : m_members) box.extend(m->bounds());
    return box;
  }
  double lipschitz() const override {
    double l = 1;
    for (const ShapePtr& m : m_members) l = std::max(l, m->lipschitz());
    return l;
  }

 private:
  std::vector<ShapePtr> m_members;
  double m_k;
};

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}

bool finite(const Vector3d& v) {
  return v.allFinite();
}

}  // namespace

double smooth_min(double a, double b, double k, double& h) {
  h = std::clamp(0.5 + 0.5 * (b - a) / k, 0.0, 1.0);
  return h * a + (1 - h) * b - k * h * (1 - h);
}

ShapePtr make_plane(const Vector3d& point, const Vector3d& normal) {
  require(finite(point) && finite(normal) && normal.norm() > 0,
          "a plane needs a finite point and a non-zero normal");
  return std::make_shared<Plane>(point, normal);
}

ShapePtr make_sphere(const Vector3d& centre, double radius) {
  require(finite(centre) && std::isfinite(radius) && radius > 0,
          "a sphere needs a finite centre and a radius > 0");
  return std::make_shared<Sphere>(centre, radius);
}

ShapePtr make_box(const Vector3d& centre, const Vector3d& half_extents) {
  require(finite(centre) && finite(half_extents) && half_extents.minCoeff() > 0,
          "a box needs a finite centre and half extents > 0");
  return std::make_shared<Box>(centre, half_extents);
}

ShapePtr make_capsule(const Vector3d& a, const Vector3d& b, double radius) {
  require(finite(a) && finite(b) && std::isfinite(radius) && radius > 0,
          "a capsule needs finite end points and a radius > 0");
  return std::make_shared<Capsule>(a, b, radius);
}

ShapePtr make_cylinder(const Vector3d& a, const Vector3d& b, double radius) {
  require(finite(a) && finite(b) && (b - a).norm() > 0 && std::isfinite(radius) && radius > 0,
          "a cylinder needs two distinct finite end points and a radius > 0");
  return std::make_shared<Cylinder>(a, b, radius);
}

ShapePtr make_ellipsoid(const Vector3d& centre, const Vector3d& semi_axes) {
  require(finite(centre) && finite(semi_axes) && semi_axes.minCoeff() > 0,
          "an ellipsoid needs a finite centre and semi-axes > 0");
  return std::make_shared<Ellipsoid>(centre, semi_axes);
}

ShapePtr make_union(std::vector<ShapePtr> members, double blend) {
  require(!members.empty(), "a union needs at least one member");
  require(std::isfinite(blend) && blend >= 0, "a smooth union's blend radius must be ≥ 0");
  for (const ShapePtr& m : members) require(m != nullptr, "a union member is missing");
  return std::make_shared<Union>(std::move(members), blend);
}

}  // namespace knit
