// Known answers for the energies' values (MODEL.md §3), each derived from the formula
// and the geometry alone: the gradient tests compare every term with its own energy, so
// these pin the energies themselves (a missing ℓ_i or ℓ_i ℓ_j factor, a wrong constant).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "knit/contact/contact_kernel.hpp"
#include "knit/contact/contact_term.hpp"
#include "knit/energy/bending.hpp"
#include "knit/energy/length.hpp"

namespace knit {
namespace {

constexpr double PI = std::numbers::pi;

// Σ_k f_k · q_k over the control points (dyn cm)
double virial(const Eigen::VectorXd& f, const Eigen::VectorXd& q) {
  return f.dot(q);
}

// control points on a circle of radius rho, `theta` apart, in the xy plane: N segments
Eigen::Matrix3Xd circle_points(double rho, double theta, int segments) {
  Eigen::Matrix3Xd cp(3, segments + 3);
  for (int k = 0; k < segments + 3; ++k)
    cp.col(k) = rho * Eigen::Vector3d(std::cos(k * theta), std::sin(k * theta), 0);
  return cp;
}

// Bending (MODEL.md §3): E_i = k_bend ℓ_i ∫₀¹ κ² dt with κ the curvature. On a circle of
// radius R, κ = 1/R everywhere, so E = k_bend (Σ ℓ_i) / R² = k_bend L / R².
//
// The geometry. A uniform cubic B-spline whose control points q_k lie on a circle of radius
// ρ, θ apart, passes through its knots y = (q_{k−1} + 4 q_k + q_{k+1}) / 6, at distance
// R = ρ (4 + 2 cos θ) / 6 from the centre, and between the knots it stays on that circle to
// O(θ⁴) (a curve with the circle's symmetry: every segment is the same arc rotated by θ).
// So the N segments run along an arc of radius R and angle N θ: L = N θ R and
// E = k_bend N θ / R. Computed independently of the code (plain Python, Simpson-11 on κ² of
// the same splines) the relative difference is 4.3e-8 at θ = 2π/100 and 1.7e-6 at
// θ = 2π/40, as the code measures too; allowed 2e-5. Without its ℓ_i factor the energy
// would be off by 1/ℓ_i = 1/(θ R): 4.3×, 5.3× and 13× on the three arcs.
TEST(KnownEnergies, BendingOfACircularArcIsKBendLOverRSquared) {
  struct Arc {
    double rho, theta;
    int segments;
  };
  for (const Arc& arc :
       {Arc{1.5, 2 * PI / 40, 20}, Arc{3.0, 2 * PI / 100, 40}, Arc{0.5, 2 * PI / 40, 30}}) {
    for (const double shrink : {1.0, 0.935}) {  // ℓ_i is the rest length: shrunk in relaxation
      ModelBuilder b;
      b.add_yarn(circle_points(arc.rho, arc.theta, arc.segments));
      const Model m = b.build(Params{}, shrink);
      const Eigen::VectorXd q = b.positions();
      const double radius = arc.rho * (4 + 2 * std::cos(arc.theta)) / 6;
      const double length = arc.segments * arc.theta * radius;  // unshrunk arclength
      const double k_bend = m.params.material.k_bend;
      const double expected = k_bend * shrink * length / (radius * radius);
      const std::string what = "rho " + std::to_string(arc.rho) + ", theta " +
                               std::to_string(arc.theta) + ", shrink " + std::to_string(shrink);
      ASSERT_NEAR(m.total_length(), shrink * length, 1e-5 * length) << what;
      // the per-segment kernel and the assembled (vectorised) term
      double sum = 0;
      for (int i = 0; i < m.num_seg(); ++i)
        sum += bending_kernel(gather_segment(q, m.seg_cp[i]), m.rest_length[i], k_bend, m.quad,
                              nullptr);
      EXPECT_NEAR(sum, expected, 2e-5 * expected) << what;
      BendingEnergy term;
      Eigen::VectorXd f = Eigen::VectorXd::Zero(q.size());
      const double e = term.add_force(m, q, Eigen::VectorXd::Zero(q.size()), 0.0, f);
      EXPECT_NEAR(e, expected, 2e-5 * expected) << what;
      // the force has the right size too: scaling the yarn by λ about any point scales κ by
      // 1/λ, so E(λq) = E(q)/λ² and Σ f·q = −dE(λq)/dλ at λ = 1 = 2E
      EXPECT_NEAR(virial(f, q), 2 * expected, 4e-5 * expected) << what;
    }
  }
}

// Length (MODEL.md §3): E_i = k_len ∫₀¹ (1 − |y_i'| / ℓ_i)² dt. Equally spaced collinear
// control points s apart give |y'| = s exactly; the model measures ℓ_i = s. Stretched
// uniformly by λ, |y'| = λ s on every segment, so E = N k_len (1 − λ)² (no ℓ_i factor:
// the integrand is dimensionless); shrunk rest lengths c ℓ_i at λ = 1 give
// N k_len (1 − 1/c)². The force: E(σ q) = N k_len (1 − σ λ)² for a further scaling σ, so
// Σ f·q = −dE/dσ at σ = 1 = 2 N k_len λ (1 − λ).
TEST(KnownEnergies, LengthOfAUniformlyStretchedStraightYarn) {
  const int segments = 17;
  const double spacing = 0.37;
  Eigen::Matrix3Xd cp(3, segments + 3);
  const Eigen::Vector3d dir = Eigen::Vector3d(1, 2, -0.5).normalized();
  for (int k = 0; k < segments + 3; ++k) cp.col(k) = (k - 1) * spacing * dir;
  ModelBuilder b;
  b.add_yarn(cp);
  const Eigen::VectorXd q0 = b.positions();
  for (const double shrink : {1.0, 0.935}) {
    const Model m = b.build(Params{}, shrink);
    const double k_len = m.params.material.k_len;
    for (const double stretch : {1.0, 1.1, 0.8}) {
      if (shrink == 1.0 && stretch == 1.0) continue;
      const Eigen::VectorXd q = stretch * q0;
      const double strain = 1 - stretch / shrink;  // 1 − |y'|/ℓ on every segment
      const double expected = segments * k_len * strain * strain;
      LengthEnergy term;
      Eigen::VectorXd f = Eigen::VectorXd::Zero(q.size());
      const double e = term.add_force(m, q, Eigen::VectorXd::Zero(q.size()), 0.0, f);
      const std::string what =
          "shrink " + std::to_string(shrink) + ", stretch " + std::to_string(stretch);
      EXPECT_NEAR(e, expected, 1e-10 * expected) << what;
      double sum = 0;
      for (int i = 0; i < m.num_seg(); ++i)
        sum +=
            length_kernel(gather_segment(q, m.seg_cp[i]), m.rest_length[i], k_len, m.quad, nullptr);
      EXPECT_NEAR(sum, expected, 1e-10 * expected) << what;
      const double expected_virial = 2 * segments * k_len * (stretch / shrink) * strain;
      EXPECT_NEAR(virial(f, q), expected_virial, 1e-9 * std::abs(expected_virial)) << what;
    }
  }
}

// Contact between two parallel straight yarns a distance s < 2r apart (MODEL.md §3):
//   E = k_contact Σ_ij ℓ_i ℓ_j ∫∫ f(|y_j − y_i| / 2r) dt dt'
// For straight, uniformly parameterised yarns ℓ_i dt is arclength, so over two aligned
// yarns of length L this is k_contact ∫₀ᴸ∫₀ᴸ g(u − u') du du' with g(x) = f(√(s² + x²)/2r),
// which vanishes for |x| ≥ x_m = √(4r² − s²) < L:
//   E = k_contact ∫ (L − |x|) g(x) dx = k_contact (L G₀ − G₁),
//   G₀ = ∫ g dx = 2 [4r²/s · atan(x_m/s) + (s² x_m + x_m³/3)/4r² − 2 x_m],
//   G₁ = ∫ |x| g dx = 4r² [−ln X₀ + (1 − X₀²)/2 − 2(1 − X₀)],   X₀ = s²/4r²
// (with D² = (s² + x²)/4r², f = 1/D² + D² − 2 integrates in closed form).
double parallel_contact_energy(double k_contact, double r, double s, double length) {
  const double four_r2 = 4 * r * r;
  const double xm = std::sqrt(four_r2 - s * s);
  const double g0 =
      2 * (four_r2 / s * std::atan(xm / s) + (s * s * xm + xm * xm * xm / 3) / four_r2 - 2 * xm);
  const double x0 = s * s / four_r2;
  const double g1 = four_r2 * (-std::log(x0) + 0.5 * (1 - x0 * x0) - 2 * (1 - x0));
  return k_contact * (length * g0 - g1);
}

struct ParallelYarns {
  Model model;
  Eigen::VectorXd q;
  int first_b = 0;  // first coordinate of yarn b
};

// two straight yarns of `segments` segments `spacing` long along x, yarn b at y = s: the
// curves run exactly over x ∈ [0, segments · spacing]
ParallelYarns parallel_yarns(double s, int segments, double spacing, int contact_points) {
  ModelBuilder b;
  for (const double y : {0.0, s}) {
    Eigen::Matrix3Xd cp(3, segments + 3);
    for (int k = 0; k < segments + 3; ++k) cp.col(k) = Eigen::Vector3d((k - 1) * spacing, y, 0);
    b.add_yarn(cp);
  }
  Params p;
  p.discretisation.contact_points = contact_points;
  ParallelYarns y{b.build(p), b.positions(), 0};
  y.first_b = 3 * y.model.yarns[1].cp_begin;
  return y;
}

// The code integrates with the midpoint rule (Params::contact_points per segment). Its
// error on this integrand, computed independently (plain Python, the same sum), is
// 4.2e-4 (s = 0.8·2r) and 4.9e-4 (0.6·2r) relative with 10 points, 1.1e-4 and 0.7e-4 with
// 20: O(h²). Allowed 1e-3 and 3e-4. Segments 0.3 cm long (> 2r: no pair within one yarn
// is in contact), so the missing-ℓ_iℓ_j mutation would be off by 1/0.09 = 11×.
TEST(KnownEnergies, ContactOfTwoParallelYarnsMatchesTheDoubleIntegral) {
  const Params defaults;
  const double r = defaults.material.radius, k = defaults.material.k_contact;
  const int segments = 8;
  const double spacing = 0.3, length = segments * spacing;
  for (const double ratio : {0.8, 0.6}) {
    for (const auto [points, tolerance] : {std::pair{10, 1e-3}, std::pair{20, 3e-4}}) {
      const double s = ratio * 2 * r;
      const ParallelYarns y = parallel_yarns(s, segments, spacing, points);
      const Model& m = y.model;
      const double expected = parallel_contact_energy(k, r, s, length);
      const std::string what =
          "d = " + std::to_string(ratio) + ", " + std::to_string(points) + " points";
      // the plain dense kernel over every non-neighbour segment pair
      double dense = 0;
      for (int i = 0; i < m.num_seg(); ++i)
        for (int j = i + 1; j < m.num_seg(); ++j)
          if (!m.neighbours(i, j))
            dense += contact_pair_energy(gather_segment(y.q, m.seg_cp[i]),
                                         gather_segment(y.q, m.seg_cp[j]), m.rest_length[i],
                                         m.rest_length[j], m.params, m.contact_quad);
      EXPECT_NEAR(dense, expected, tolerance * expected) << what;
      // the assembled term (BVH culling, vectorised kernel)
      ContactTerm term(m);
      Eigen::VectorXd f = Eigen::VectorXd::Zero(y.q.size());
      const double e = term.add_force(m, y.q, Eigen::VectorXd::Zero(y.q.size()), 0.0, f);
      EXPECT_NEAR(e, expected, tolerance * expected) << what;
      EXPECT_NEAR(term.last_stats().min_distance_ratio, ratio, 1e-12) << what;
    }
  }
  // apart by 2r or more, nothing
  const ParallelYarns apart = parallel_yarns(2.001 * r, segments, spacing, 10);
  ContactTerm term(apart.model);
  EXPECT_EQ(term.energy(apart.model, apart.q, 0.0), 0.0);
}

// The contact force pushes the yarns apart with −dE/ds: the net force on yarn b along y is
// −dE/ds of the closed form above (differentiated by a central difference of the formula).
// Midpoint-rule error on the force, computed as above: 5.2e-3 (s = 0.8·2r) and 0.9e-3
// (0.6·2r) relative with 10 points; allowed 1e-2.
TEST(KnownEnergies, ContactPushesParallelYarnsApartWithMinusDEnergyDs) {
  const Params defaults;
  const double r = defaults.material.radius, k = defaults.material.k_contact;
  const int segments = 8;
  const double spacing = 0.3, length = segments * spacing;
  for (const double ratio : {0.8, 0.6}) {
    const double s = ratio * 2 * r, ds = 1e-6;
    const double expected = -(parallel_contact_energy(k, r, s + ds, length) -
                              parallel_contact_energy(k, r, s - ds, length)) /
                            (2 * ds);
    ASSERT_GT(expected, 0);
    const ParallelYarns y = parallel_yarns(s, segments, spacing, 10);
    ContactTerm term(y.model);
    Eigen::VectorXd f = Eigen::VectorXd::Zero(y.q.size());
    term.add_force(y.model, y.q, Eigen::VectorXd::Zero(y.q.size()), 0.0, f);
    Eigen::Vector3d on_b = Eigen::Vector3d::Zero();
    for (Eigen::Index c = y.first_b; c < f.size(); c += 3) on_b += f.segment<3>(c);
    EXPECT_NEAR(on_b.y(), expected, 1e-2 * expected) << "d = " << ratio;
    EXPECT_NEAR(on_b.x(), 0.0, 1e-9 * expected) << "d = " << ratio;
    EXPECT_NEAR(on_b.z(), 0.0, 1e-9 * expected) << "d = " << ratio;
  }
}

}  // namespace
}  // namespace knit
