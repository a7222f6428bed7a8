// ContactTerm: assembled derivatives, BVH against brute force, determinism, conservation
// laws and a push test.
#include "knit/contact/contact_term.hpp"

#include <gtest/gtest.h>

#include <tbb/global_control.h>
#include <tbb/task_arena.h>
#include <Eigen/Geometry>

#include <cmath>
#include <random>
#include <string>

#include "knit/contact/contact_kernel.hpp"
#include "knit/contact/contact_samples.hpp"

namespace knit {
namespace {

// largest |entry| (a plain loop: GCC 12 warns falsely inside Eigen's AVX-512 max reduction)
template <class V>
double max_abs(const V& v) {
  double m = 0;
  for (Eigen::Index k = 0; k < v.size(); ++k) m = std::max(m, std::abs(v[k]));
  return m;
}

struct Sample {
  Model model;
  Eigen::VectorXd q;
};

Sample make(const ModelBuilder& builder, const Params& params = Params{}) {
  return {builder.build(params), builder.positions()};
}

Eigen::VectorXd random_vector(int n, double sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, sigma);
  Eigen::VectorXd v(n);
  for (int k = 0; k < n; ++k) v[k] = normal(rng);
  return v;
}

Eigen::VectorXd force_of(ContactTerm& term, const Sample& s, const Eigen::VectorXd& v,
                         double* energy = nullptr) {
  Eigen::VectorXd f = Eigen::VectorXd::Zero(s.q.size());
  const double e = term.add_force(s.model, s.q, v, 0.0, f);
  if (energy) *energy = e;
  return f;
}

// total contact damping D over all non-neighbour pairs, from the plain kernel
double total_damping(const Model& m, const Eigen::VectorXd& q, const Eigen::VectorXd& v) {
  double d = 0;
  for (int i = 0; i < m.num_seg(); ++i)
    for (int j = i + 1; j < m.num_seg(); ++j) {
      if (m.neighbours(i, j)) continue;
      d += contact_pair_damping(gather_segment(q, m.seg_cp[i]), gather_segment(q, m.seg_cp[j]),
                                gather_segment(v, m.seg_cp[i]), gather_segment(v, m.seg_cp[j]),
                                m.rest_length[i], m.rest_length[j], m.params, m.contact_quad);
    }
  return d;
}

std::string dof_name(int k) {
  return "coordinate " + std::to_string(k) + " (control point " + std::to_string(k / 3) +
         ", axis " + "xyz"[k % 3] + ")";
}

// a small knit-like patch pressed into contact: 2 rows × 2 loops, d ≈ 0.8
Sample pressed_patch() {
  return make(knit_like_sample(2, 2, 8, 0.125, 0.8));
}

TEST(ContactTerm, NameAndEmptyStats) {
  const Sample s = pressed_patch();
  ContactTerm term(s.model);
  EXPECT_EQ(term.name(), "contact");
  EXPECT_EQ(term.last_stats().point_pairs_in_contact, 0);
  EXPECT_TRUE(std::isinf(term.last_stats().min_distance_ratio));
}

TEST(ContactTerm, RejectsTooManyContactPoints) {
  Params p;
  p.discretisation.contact_points = ContactTerm::MAX_CONTACT_POINTS + 1;
  EXPECT_THROW(ContactTerm(make(knit_like_sample(1, 1, 8, 0.125), p).model), std::invalid_argument);
}

TEST(ContactTerm, AssembledForceIsMinusEnergyGradient) {
  const Sample s = pressed_patch();
  ContactTerm term(s.model);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(s.q.size());
  const Eigen::VectorXd f = force_of(term, s, zero);
  ASSERT_GT(term.last_stats().point_pairs_in_contact, 100);
  ASSERT_GT(max_abs(f), 0) << "no contact force: nothing to compare";
  const double scale = max_abs(f);
  const double h = 1e-7;
  for (int k = 0; k < s.q.size(); ++k) {
    Eigen::VectorXd qp = s.q, qm = s.q;
    qp[k] += h;
    qm[k] -= h;
    const double fd = -(term.energy(s.model, qp, 0.0) - term.energy(s.model, qm, 0.0)) / (2 * h);
    EXPECT_NEAR(f[k], fd, 1e-6 * scale) << dof_name(k);
  }
}

TEST(ContactTerm, AssembledDampingForceIsMinusDampingGradient) {
  const Sample s = pressed_patch();
  ContactTerm term(s.model);
  const Eigen::VectorXd v = random_vector(s.q.size(), 5.0, 11);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(s.q.size());
  const Eigen::VectorXd fdamp = force_of(term, s, v) - force_of(term, s, zero);
  ASSERT_GT(max_abs(fdamp), 0);
  const double scale = max_abs(fdamp);
  const double h = 1e-3;  // D is quadratic in v: central differences are exact
  for (int k = 0; k < v.size(); ++k) {
    Eigen::VectorXd vp = v, vm = v;
    vp[k] += h;
    vm[k] -= h;
    const double fd =
        -(total_damping(s.model, s.q, vp) - total_damping(s.model, s.q, vm)) / (2 * h);
    EXPECT_NEAR(fdamp[k], fd, 1e-8 * scale) << dof_name(k);
  }
}

// BVH and brute force agree on the point pairs in contact, the energy and the force
void expect_bvh_matches_brute(const Sample& s, const Eigen::VectorXd& v, const std::string& what,
                              const Eigen::VectorXd* build_at = nullptr) {
  ContactTerm bvh(s.model, ContactCulling::BVH), brute(s.model, ContactCulling::BRUTE_FORCE);
  bvh.set_record_point_pairs(true);
  brute.set_record_point_pairs(true);
  if (build_at) {
    // build the tree on other positions, so that this evaluation is a refit
    Eigen::VectorXd f = Eigen::VectorXd::Zero(s.q.size());
    bvh.add_force(s.model, *build_at, v, 0.0, f);
  }
  double e_bvh = 0, e_brute = 0;
  const Eigen::VectorXd f_bvh = force_of(bvh, s, v, &e_bvh);
  const Eigen::VectorXd f_brute = force_of(brute, s, v, &e_brute);
  const ContactStats& a = bvh.last_stats();
  const ContactStats& b = brute.last_stats();
  ASSERT_GT(b.point_pairs_in_contact, 0) << what << ": no contact, nothing to compare";
  EXPECT_EQ(bvh.last_point_pairs(), brute.last_point_pairs()) << what;
  EXPECT_EQ(a.point_pairs_in_contact, b.point_pairs_in_contact) << what;
  EXPECT_EQ(static_cast<long long>(bvh.last_point_pairs().size()), a.point_pairs_in_contact);
  EXPECT_NEAR(a.min_distance_ratio, b.min_distance_ratio, 1e-14) << what;
  EXPECT_NEAR(e_bvh, e_brute, 1e-12 * std::abs(e_brute)) << what;
  const double scale = max_abs(f_brute);
  for (int k = 0; k < f_brute.size(); ++k)
    ASSERT_NEAR(f_bvh[k], f_brute[k], 1e-11 * scale) << what << ": " << dof_name(k);
  // culling must visit far fewer pairs than brute force
  EXPECT_LT(a.candidate_segment_pairs, b.candidate_segment_pairs) << what;
  EXPECT_LT(a.point_pairs_tested, b.point_pairs_tested / 4) << what;
}

TEST(ContactTerm, BvhMatchesBruteForceOnRandomTangles) {
  for (unsigned seed : {1u, 2u, 3u, 4u}) {
    const Sample s = make(random_tangle(4, 30, 3.0, seed));
    const Eigen::VectorXd v = random_vector(s.q.size(), 3.0, seed + 100);
    expect_bvh_matches_brute(s, v, "random tangle, seed " + std::to_string(seed));
  }
}

TEST(ContactTerm, BvhMatchesBruteForceOnKnitSample) {
  const Sample s = make(knit_like_sample(4, 4, 8, 0.125, 0.9));
  const Eigen::VectorXd v = random_vector(s.q.size(), 3.0, 7);
  expect_bvh_matches_brute(s, v, "knit sample");
}

TEST(ContactTerm, BvhMatchesBruteForceAfterRefit) {
  // the tree is built on one configuration, then refit on a strongly moved one
  Params p;
  p.discretisation.contact_points = 16;
  const Sample s0 = make(random_tangle(3, 30, 3.0, 9), p);
  Sample s = s0;
  s.q += random_vector(s.q.size(), 0.3, 10);
  const Eigen::VectorXd v = random_vector(s.q.size(), 3.0, 12);
  expect_bvh_matches_brute(s, v, "tangle after refit", &s0.q);
}

TEST(ContactTerm, BvhMatchesBruteForceWithOddPointCountsAndWithoutDamping) {
  // the vectorised kernel pads the points of a segment to whole vectors, and has a path
  // without damping (k_dt = k_dn = 0): cover both against the plain dense kernel
  for (int points : {1, 3, 7, 13, 20}) {
    for (bool damping : {true, false}) {
      Params p;
      p.discretisation.contact_points = points;
      if (!damping) p.material.k_dt = p.material.k_dn = 0;
      const Sample s = make(random_tangle(3, 25, 2.5, 30 + points), p);
      const Eigen::VectorXd v = random_vector(s.q.size(), 3.0, 50 + points);
      expect_bvh_matches_brute(
          s, v, std::to_string(points) + " points" + (damping ? "" : ", no damping"));
    }
  }
}

TEST(ContactTerm, KeptCandidateListMatchesBruteForceAfterSmallMotion) {
  // built at s0, evaluated after every control point moved by less than δ/2 per axis (so
  // every contact point did too: they are convex combinations): the list is kept
  const Sample s0 = make(knit_like_sample(4, 4, 8, 0.125, 0.9));
  const double half_margin = 0.5 * ContactTerm::DEFAULT_MARGIN_RADII * 0.125;
  Sample s = s0;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> uni(-0.95 * half_margin, 0.95 * half_margin);
  for (Eigen::Index k = 0; k < s.q.size(); ++k) s.q[k] += uni(rng);
  const Eigen::VectorXd v = random_vector(s.q.size(), 3.0, 6);
  expect_bvh_matches_brute(s, v, "knit sample, kept list", &s0.q);
  ContactTerm term(s.model);
  Eigen::VectorXd f = Eigen::VectorXd::Zero(s.q.size());
  term.add_force(s.model, s0.q, v, 0.0, f);
  EXPECT_TRUE(term.last_stats().candidates_rebuilt);
  term.add_force(s.model, s.q, v, 0.0, f);
  EXPECT_FALSE(term.last_stats().candidates_rebuilt) << "the motion was below δ/2";
}

// Verlet-list reuse is exact: along a drifting, jittered trajectory, a term that keeps its
// candidate list between rebuilds gives bitwise the same forces, energy and counts as a
// fresh term (which always builds a new list), with the list both kept and rebuilt.
TEST(ContactTerm, KeptCandidateListGivesBitwiseTheSameForcesAsARebuild) {
  for (double margin_radii : {0.25, ContactTerm::DEFAULT_MARGIN_RADII, 1.0, 0.0}) {
    const Sample s0 = make(knit_like_sample(4, 5, 8, 0.125, 0.85));
    const double margin = margin_radii * 0.125;
    ContactTerm kept(s0.model);
    kept.set_candidate_margin(margin);
    EXPECT_EQ(kept.candidate_margin(), margin);
    Sample s = s0;
    const Eigen::VectorXd drift = random_vector(s.q.size(), 1.0, 77).cwiseSign();
    int reused = 0, rebuilt = 0;
    for (int step = 0; step < 16; ++step) {
      const Eigen::VectorXd v = random_vector(s.q.size(), 3.0, 200 + step);
      double e_kept = 0, e_fresh = 0;
      const Eigen::VectorXd f_kept = force_of(kept, s, v, &e_kept);
      ContactTerm fresh(s.model);
      const Eigen::VectorXd f_fresh = force_of(fresh, s, v, &e_fresh);
      const ContactStats &a = kept.last_stats(), &b = fresh.last_stats();
      const std::string what =
          "margin " + std::to_string(margin_radii) + " r, step " + std::to_string(step);
      ASSERT_GT(b.point_pairs_in_contact, 0) << what;
      (a.candidates_rebuilt ? rebuilt : reused) += 1;
      EXPECT_EQ(e_kept, e_fresh) << what;
      EXPECT_EQ(a.candidate_segment_pairs, b.candidate_segment_pairs) << what;
      EXPECT_EQ(a.point_pairs_tested, b.point_pairs_tested) << what;
      EXPECT_EQ(a.point_pairs_in_contact, b.point_pairs_in_contact) << what;
      EXPECT_EQ(a.min_distance_ratio, b.min_distance_ratio) << what;
      for (int k = 0; k < f_kept.size(); ++k)
        ASSERT_EQ(f_kept[k], f_fresh[k]) << what << ": " << dof_name(k);
      // a drift of 0.048 r per axis per step plus jitter: with δ/2 = 0.125 r a rebuild
      // every 2 or 3 steps, with δ/2 = 0.25 r every 5, with δ/2 = 0.5 r after about 9
      s.q += 0.006 * drift + random_vector(s.q.size(), 0.001, 300 + step);
    }
    if (margin > 0) {
      EXPECT_GT(reused, 0) << "margin " << margin_radii << " r: never kept";
    }
    EXPECT_GT(rebuilt, 1) << "margin " << margin_radii << " r: never rebuilt";
  }
}

// Unless set, the margin adapts: along a fast drift that outruns the default margin every
// evaluation it grows (and the list is kept for some evaluations), and once the knit is
// still it shrinks back to the default; the forces stay bitwise those of a fresh term.
TEST(ContactTerm, AdaptiveMarginGrowsWithFastMotionAndShrinksWhenStill) {
  const Sample s0 = make(knit_like_sample(4, 5, 8, 0.125, 0.85));
  const double r = 0.125;
  ContactTerm adaptive(s0.model);
  EXPECT_EQ(adaptive.candidate_margin(), ContactTerm::DEFAULT_MARGIN_RADII * r);
  Sample s = s0;
  const Eigen::VectorXd drift = random_vector(s.q.size(), 1.0, 78).cwiseSign();
  auto evaluate = [&](const std::string& what) {
    const Eigen::VectorXd v = random_vector(s.q.size(), 3.0, 400);
    double e_adaptive = 0, e_fresh = 0;
    const Eigen::VectorXd f_adaptive = force_of(adaptive, s, v, &e_adaptive);
    ContactTerm fresh(s.model);
    const Eigen::VectorXd f_fresh = force_of(fresh, s, v, &e_fresh);
    ASSERT_EQ(e_adaptive, e_fresh) << what;
    EXPECT_EQ(adaptive.last_stats().point_pairs_in_contact,
              fresh.last_stats().point_pairs_in_contact)
        << what;
    for (int k = 0; k < f_adaptive.size(); ++k)
      ASSERT_EQ(f_adaptive[k], f_fresh[k]) << what << ": " << dof_name(k);
  };
  // 0.4 r per axis per evaluation: more than the default δ/2 = 0.25 r
  const long long before_fast = adaptive.candidate_rebuilds();
  for (int step = 0; step < 24; ++step) {
    evaluate("fast, step " + std::to_string(step));
    s.q += 0.05 * drift;
  }
  const double grown = adaptive.candidate_margin();
  EXPECT_GT(grown, ContactTerm::DEFAULT_MARGIN_RADII * r);
  EXPECT_LE(grown, ContactTerm::MAX_ADAPTIVE_MARGIN_RADII * r * (1 + 1e-12));
  EXPECT_LT(adaptive.candidate_rebuilds() - before_fast, 20) << "the grown margin kept the list";
  // still: a tiny jitter, each evaluation near the last
  for (int step = 0; step < 200; ++step) {
    evaluate("still, step " + std::to_string(step));
    s.q += random_vector(s.q.size(), 0.002, 500 + step);
  }
  EXPECT_LT(adaptive.candidate_margin(), grown);
  EXPECT_EQ(adaptive.candidate_margin(), ContactTerm::DEFAULT_MARGIN_RADII * r);
  // a margin that was set stays
  ContactTerm fixed(s0.model);
  fixed.set_candidate_margin(0.1 * r);
  Eigen::VectorXd f = Eigen::VectorXd::Zero(s0.q.size());
  Eigen::VectorXd q = s0.q;
  for (int step = 0; step < 10; ++step) {
    f.setZero();
    fixed.add_force(s0.model, q, Eigen::VectorXd::Zero(q.size()), 0.0, f);
    q += 0.05 * drift;
  }
  EXPECT_EQ(fixed.candidate_margin(), 0.1 * r);
  EXPECT_EQ(fixed.candidate_rebuilds(), 10);
}

TEST(ContactTerm, RejectsANegativeCandidateMargin) {
  const Sample s = pressed_patch();
  ContactTerm term(s.model);
  EXPECT_THROW(term.set_candidate_margin(-0.01), std::invalid_argument);
  EXPECT_THROW(term.set_candidate_margin(std::nan("")), std::invalid_argument);
}

TEST(ContactTerm, ResultsDoNotDependOnThreadCount) {
  const Sample s = make(knit_like_sample(6, 6, 8, 0.125, 0.9));
  const Eigen::VectorXd v = random_vector(s.q.size(), 3.0, 21);
  const Eigen::VectorXd x = random_vector(s.q.size(), 1.0, 22);
  Eigen::VectorXd f1, f2, k1 = Eigen::VectorXd::Zero(s.q.size()), k2 = k1;
  std::vector<Matrix12d> b1(s.model.num_seg(), Matrix12d::Zero()), b2 = b1;
  double e1 = 0, e2 = 0;
  ContactStats st1, st2;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    ContactTerm term(s.model);
    term.set_operator_stiffness(true);
    f1 = force_of(term, s, v, &e1);
    st1 = term.last_stats();
    term.add_stiffness_product(s.model, x, k1);
    term.add_operator_segment_stiffness(s.model, b1);
  }
  {
    // an explicit arena: a global_control alone does not raise the concurrency of the
    // thread's implicit arena after its first use (with 1 thread above)
    tbb::global_control two(tbb::global_control::max_allowed_parallelism, 2);
    tbb::task_arena(2).execute([&] {
      ContactTerm term(s.model);
      term.set_operator_stiffness(true);
      force_of(term, s, v);  // the second evaluation keeps the candidate list
      f2 = force_of(term, s, v, &e2);
      st2 = term.last_stats();
      term.add_stiffness_product(s.model, x, k2);
      term.add_operator_segment_stiffness(s.model, b2);
    });
  }
  // and the IMEX_CONTACT step's stiffness operator
  for (int k = 0; k < k1.size(); ++k) ASSERT_EQ(k1[k], k2[k]) << dof_name(k);
  for (int i = 0; i < s.model.num_seg(); ++i) ASSERT_TRUE(b1[i] == b2[i]) << "segment " << i;
  ASSERT_GT(st1.point_pairs_in_contact, 0);
  EXPECT_EQ(e1, e2);
  EXPECT_EQ(st1.point_pairs_in_contact, st2.point_pairs_in_contact);
  EXPECT_EQ(st1.point_pairs_tested, st2.point_pairs_tested);
  EXPECT_EQ(st1.min_distance_ratio, st2.min_distance_ratio);
  for (int k = 0; k < f1.size(); ++k) ASSERT_EQ(f1[k], f2[k]) << dof_name(k);
}

TEST(ContactTerm, ConservesMomentumAndEnergyForcesHaveNoTorque) {
  for (unsigned seed : {5u, 6u}) {
    const Sample s = make(random_tangle(3, 30, 2.5, seed));
    ContactTerm term(s.model);
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(s.q.size());
    const Eigen::VectorXd v = random_vector(s.q.size(), 3.0, seed);
    const Eigen::VectorXd f = force_of(term, s, zero);
    const Eigen::VectorXd fv = force_of(term, s, v);
    ASSERT_GT(term.last_stats().point_pairs_in_contact, 0);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero(), sum_v = Eigen::Vector3d::Zero();
    Eigen::Vector3d torque = Eigen::Vector3d::Zero();
    double magnitude = 0, moment = 0;
    for (int k = 0; k < s.model.num_cp(); ++k) {
      const Eigen::Vector3d fk = f.segment<3>(3 * k), xk = s.q.segment<3>(3 * k);
      sum += fk;
      sum_v += fv.segment<3>(3 * k);
      torque += xk.cross(fk);
      magnitude += fk.norm() + fv.segment<3>(3 * k).norm();
      moment += xk.norm() * fk.norm();
    }
    ASSERT_GT(magnitude, 0);
    EXPECT_LE(sum.norm(), 1e-12 * magnitude) << "seed " << seed;
    EXPECT_LE(sum_v.norm(), 1e-12 * magnitude) << "seed " << seed << " (with damping)";
    // rotation invariance of E: Σ x × (−∂E/∂x) = 0 (contact damping is a friction
    // stand-in and does exert a couple, so only the conservative part is checked)
    EXPECT_LE(torque.norm(), 1e-12 * moment) << "seed " << seed;
  }
}

TEST(ContactTerm, DampingOnlyRemovesEnergy) {
  const Sample s = make(random_tangle(3, 30, 2.5, 8));
  ContactTerm term(s.model);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(s.q.size());
  const Eigen::VectorXd f0 = force_of(term, s, zero);
  for (unsigned seed = 0; seed < 5; ++seed) {
    const Eigen::VectorXd v = random_vector(s.q.size(), 10.0, 40 + seed);
    const Eigen::VectorXd fdamp = force_of(term, s, v) - f0;
    double power = 0;  // vᵀf as a plain loop (see max_abs)
    for (Eigen::Index k = 0; k < v.size(); ++k) power += v[k] * fdamp[k];
    const double d = total_damping(s.model, s.q, v);
    ASSERT_GT(d, 0);
    EXPECT_LT(power, 0) << "seed " << seed;
    EXPECT_NEAR(power, -2 * d, 1e-9 * d) << "seed " << seed;
  }
}

// Contact energy per unit length of a straight yarn lying parallel to an infinite straight
// yarn at distance s < 2r (MODEL.md §3 with ℓ dt = arclength): k_contact ∫ g(x) dx with
// g(x) = f(√(s² + x²)/2r), in closed form (see tests/energy/known_energies_test.cpp)
//   G₀(s) = 2 [4r²/s · atan(x_m/s) + (s² x_m + x_m³/3)/4r² − 2 x_m],  x_m = √(4r² − s²).
double parallel_contact_energy_per_length(double k_contact, double r, double s) {
  const double four_r2 = 4 * r * r;
  if (s * s >= four_r2) return 0;
  const double xm = std::sqrt(four_r2 - s * s);
  return k_contact * 2 *
         (four_r2 / s * std::atan(xm / s) + (s * s * xm + xm * xm * xm / 3) / four_r2 - 2 * xm);
}

TEST(ContactTerm, PushedYarnsNeverComeCloserThanHalfTheContactDistance) {
  // a free yarn pressed by 5000 dyn per cm of yarn (≈ 5 g-force per cm, about 850 times its
  // weight) into the groove between two pinned, touching parallel yarns (on a single
  // pinned yarn it would slide off sideways), from rest at d = 1.05; symplectic Euler with
  // only the contact term (energy + damping) and the push
  const Params p;
  const double r = p.material.radius, two_r = 2 * r;
  const double half_gap = 0.51 * two_r;  // bottom yarns 1.02·2r apart (centre to centre)
  const double height = std::sqrt(std::pow(1.05 * two_r, 2) - half_gap * half_gap);
  const double h = 0.3;
  ModelBuilder builder;
  for (double y : {-half_gap, half_gap}) {
    Eigen::Matrix3Xd bottom(3, 19);
    for (int k = 0; k < bottom.cols(); ++k) bottom.col(k) = Eigen::Vector3d((k - 9) * h, y, 0);
    builder.add_yarn(bottom);
  }
  Eigen::Matrix3Xd top(3, 11);
  for (int k = 0; k < top.cols(); ++k) top.col(k) = Eigen::Vector3d((k - 5) * h, 0, height);
  builder.add_yarn(top);
  const Model model = builder.build(p);
  Eigen::VectorXd q = builder.positions();
  Eigen::VectorXd v = Eigen::VectorXd::Zero(q.size());
  const int first_free = 3 * model.yarns[2].cp_begin;
  const int free_dofs = static_cast<int>(q.size()) - first_free;
  const double push = 5000;  // dyn/cm
  ContactTerm term(model);
  // The first turning point, from energy alone: released at rest out of contact, the yarn
  // (a rigid rod: the push and the support are uniform along it) stops where the push's
  // work per unit length equals the contact energy it has stored against the two bottom
  // yarns, p (z₀ − z) = 2 G₀(√(a² + z²)) with a = half_gap (contact damping, k_dn = 0.03,
  // takes a negligible share). Solved by bisection: d = 0.7104. With a 16× stiffer contact
  // it would be 0.936.
  auto stored_minus_work = [&](double z) {
    return 2 * parallel_contact_energy_per_length(p.material.k_contact, r,
                                                  std::hypot(half_gap, z)) -
           push * (height - z);
  };
  double lo = 0.01, hi = std::sqrt(two_r * two_r - half_gap * half_gap);  // d = 1 at hi
  for (int it = 0; it < 100; ++it) {
    const double mid = 0.5 * (lo + hi);
    if (stored_minus_work(mid) > 0)
      lo = mid;  // still pressed deeper than the push's work can pay for: turns higher up
    else
      hi = mid;
  }
  const double turning_d = std::hypot(half_gap, 0.5 * (lo + hi)) / two_r;
  double first_min_d = std::numeric_limits<double>::infinity();
  double min_d = std::numeric_limits<double>::infinity();
  const double dt = 1e-5;
  for (int step = 0; step < 3000; ++step) {
    Eigen::VectorXd f = Eigen::VectorXd::Zero(q.size());
    term.add_force(model, q, v, 0.0, f);
    min_d = std::min(min_d, term.last_stats().min_distance_ratio);
    if (step < 1500) first_min_d = min_d;  // the first swing in and out (MEASURED below)
    for (int k = first_free; k < q.size(); ++k) {
      const double m = model.mass[k / 3];
      const double fk = f[k] + (k % 3 == 2 ? -push * m / p.material.density : 0.0);
      v[k] += dt * fk / m;
    }
    q.tail(free_dofs) += dt * v.tail(free_dofs);
    ASSERT_TRUE(q.allFinite()) << "step " << step;
  }
  // measured: the first swing turns at d = 0.7076 (step ≈ 900; by step 1500 the yarn is
  // back at d = 0.83), 0.4 % inside the prediction (the yarn tilts a little, and the
  // midpoint rule is 0.1 % off the integral); allowed ±0.015
  EXPECT_NEAR(first_min_d, turning_d, 0.015) << "predicted d = " << turning_d;
  // it keeps bouncing with next to no damping and rocks a little, so later swings reach
  // slightly deeper: measured min over 3000 steps 0.7021; allowed down to 0.68
  EXPECT_GE(min_d, 0.68);
  // the free yarn still lies in the groove, above the pinned ones
  for (int k = model.yarns[2].cp_begin + 1; k + 1 < model.yarns[2].cp_end; ++k) {
    EXPECT_GT(q[3 * k + 2], 0.0) << "control point " << k;
    EXPECT_LT(std::abs(q[3 * k + 1]), half_gap) << "control point " << k;
  }
}

}  // namespace
}  // namespace knit

namespace knit {
namespace {

// The oracle: Σ over segment pairs of the dense pair Hessians made semidefinite
// (contact_pair_hessian, ContactHessian::MIRRORED) applied to x; with `blocks`, also their
// parts on each segment's own control points.
Eigen::VectorXd dense_operator_product(const Sample& s, const Eigen::VectorXd& x,
                                       std::vector<Matrix12d>* blocks = nullptr) {
  const Model& m = s.model;
  Eigen::VectorXd out = Eigen::VectorXd::Zero(x.size());
  if (blocks) blocks->assign(m.num_seg(), Matrix12d::Zero());
  for (int i = 0; i < m.num_seg(); ++i)
    for (int j = i + 1; j < m.num_seg(); ++j) {
      if (m.neighbours(i, j)) continue;
      const Eigen::Matrix<double, 24, 24> hess = contact_pair_hessian(
          gather_segment(s.q, m.seg_cp[i]), gather_segment(s.q, m.seg_cp[j]), m.rest_length[i],
          m.rest_length[j], m.params, m.contact_quad, ContactHessian::MIRRORED);
      Eigen::Matrix<double, 24, 1> xij;
      xij << x.segment<12>(3 * m.seg_cp[i]), x.segment<12>(3 * m.seg_cp[j]);
      const Eigen::Matrix<double, 24, 1> y = hess * xij;
      out.segment<12>(3 * m.seg_cp[i]) += y.head<12>();
      out.segment<12>(3 * m.seg_cp[j]) += y.tail<12>();
      if (!blocks) continue;
      (*blocks)[i] += hess.topLeftCorner<12, 12>();
      (*blocks)[j] += hess.bottomRightCorner<12, 12>();
    }
  return out;
}

// The stiffness operator of the IMEX_CONTACT step against a brute-force oracle: K x for
// random x equals Σ over all non-neighbour segment pairs of the dense pair Hessians
// made semidefinite (contact_pair_hessian, ContactHessian::MIRRORED) applied to x; its segment
// parts are the oracle's blocks on each segment's own control points; and it is symmetric positive
// semidefinite (xᵀ K y = yᵀ K x, xᵀ K x ≥ 0). With and without contact damping (the
// kernels take separate paths).
class StiffnessOperator : public ::testing::TestWithParam<bool> {};

TEST_P(StiffnessOperator, MatchesTheDensePairHessians) {
  Params p;
  if (!GetParam()) p.material.k_dt = p.material.k_dn = 0;
  const Sample s = make(knit_like_sample(2, 2, 8, 0.125, 0.8), p);
  const Model& m = s.model;
  ContactTerm term(m);
  term.set_operator_stiffness(true);
  force_of(term, s, Eigen::VectorXd::Zero(s.q.size()));
  ASSERT_GT(term.last_stats().point_pairs_in_contact, 50);
  const int n = static_cast<int>(s.q.size());
  const Eigen::VectorXd x = random_vector(n, 1.0, 11);
  std::vector<Matrix12d> oracle_blocks;
  const Eigen::VectorXd oracle_x = dense_operator_product(s, x, &oracle_blocks);
  Eigen::VectorXd kx = Eigen::VectorXd::Zero(n);
  term.add_stiffness_product(m, x, kx);
  ASSERT_GT(max_abs(oracle_x), 0.0);
  EXPECT_LT(max_abs(kx - oracle_x), 1e-9 * max_abs(oracle_x));
  // the product's rows at a window of control points (as the clamps' reaction takes them)
  // from the segments that touch the window alone
  const int cp0 = m.num_cp() / 3, cp1 = cp0 + 8;
  std::vector<int> touching;
  for (int i = 0; i < m.num_seg(); ++i)
    if (m.seg_cp[i] + 3 >= cp0 && m.seg_cp[i] <= cp1) touching.push_back(i);
  Eigen::VectorXd rows = Eigen::VectorXd::Zero(n);
  term.add_stiffness_product_rows(m, x, touching, rows);
  const Eigen::VectorXd window = oracle_x.segment(3 * cp0, 3 * (cp1 - cp0 + 1));
  ASSERT_GT(max_abs(window), 0.0);
  EXPECT_LT(max_abs(rows.segment(3 * cp0, window.size()) - window), 1e-9 * max_abs(oracle_x));
  std::vector<Matrix12d> blocks(m.num_seg(), Matrix12d::Zero());
  term.add_operator_segment_stiffness(m, blocks);
  double worst = 0, scale = 0;
  for (int i = 0; i < m.num_seg(); ++i) {
    worst = std::max(worst, max_abs((blocks[i] - oracle_blocks[i]).reshaped()));
    scale = std::max(scale, max_abs(oracle_blocks[i].reshaped()));
  }
  EXPECT_LT(worst, 1e-9 * scale);
  const Eigen::VectorXd y = random_vector(n, 1.0, 12);
  Eigen::VectorXd ky = Eigen::VectorXd::Zero(n);
  term.add_stiffness_product(m, y, ky);
  EXPECT_NEAR(x.dot(ky), y.dot(kx), 1e-9 * std::abs(x.dot(kx)));
  EXPECT_GE(x.dot(kx), 0.0);
  // evaluated again where other point pairs are in contact, the products are the new
  // state's (the point pairs' arrays are rebuilt, not added to)
  const long long pairs_before = term.last_stats().point_pairs_in_contact;
  Sample moved = s;
  moved.q += random_vector(n, 0.2 * m.params.material.radius, 14);
  force_of(term, moved, Eigen::VectorXd::Zero(n));
  EXPECT_NE(term.last_stats().point_pairs_in_contact, pairs_before);
  const Eigen::VectorXd oracle_moved = dense_operator_product(moved, x);
  Eigen::VectorXd kx_moved = Eigen::VectorXd::Zero(n), rows_moved = Eigen::VectorXd::Zero(n);
  term.add_stiffness_product(m, x, kx_moved);
  term.add_stiffness_product_rows(m, x, touching, rows_moved);
  EXPECT_LT(max_abs(kx_moved - oracle_moved), 1e-9 * max_abs(oracle_moved));
  EXPECT_LT(max_abs(rows_moved.segment(3 * cp0, window.size()) -
                    oracle_moved.segment(3 * cp0, window.size())),
            1e-9 * max_abs(oracle_moved));
  // off: the product is empty
  term.set_operator_stiffness(false);
  Eigen::VectorXd none = Eigen::VectorXd::Zero(n);
  term.add_stiffness_product(m, x, none);
  EXPECT_EQ(max_abs(none), 0.0);
}

INSTANTIATE_TEST_SUITE_P(ContactTerm, StiffnessOperator, ::testing::Values(true, false),
                         [](const ::testing::TestParamInfo<bool>& info) {
                           return info.param ? "WithDamping" : "WithoutDamping";
                         });

// Evaluated with a velocity v (and damping on), the kernels form K v on the way: the product
// with that v is the dense pair Hessians' as well, and agrees with the product taken apart
// (K (2v) / 2, which is not the evaluation's velocity).
TEST(ContactTerm, StiffnessProductWithTheEvaluationsVelocityIsFormedByTheKernels) {
  const Sample s = pressed_patch();
  const Model& m = s.model;
  ASSERT_GT(m.params.material.k_dt, 0.0);
  ContactTerm term(m);
  term.set_operator_stiffness(true);
  const int n = static_cast<int>(s.q.size());
  const Eigen::VectorXd v = random_vector(n, 1.0, 13);
  force_of(term, s, v);
  ASSERT_GT(term.last_stats().point_pairs_in_contact, 50);
  const Eigen::VectorXd oracle = dense_operator_product(s, v);
  ASSERT_GT(max_abs(oracle), 0.0);
  Eigen::VectorXd kv = Eigen::VectorXd::Zero(n);
  term.add_stiffness_product(m, v, kv);
  EXPECT_LT(max_abs(kv - oracle), 1e-9 * max_abs(oracle));
  const Eigen::VectorXd v2 = 2.0 * v;
  Eigen::VectorXd k2v = Eigen::VectorXd::Zero(n);
  term.add_stiffness_product(m, v2, k2v);
  EXPECT_LT(max_abs(0.5 * k2v - kv), 1e-12 * max_abs(oracle));
  EXPECT_GT(max_abs(0.5 * k2v - kv), 0.0) << "the two paths round differently: both ran";
}

}  // namespace
}  // namespace knit

namespace knit {
namespace {

// Reuse (SolverSettings::contact_reuse): within reach of the last exact evaluation the
// force is its first-order model. Where the perturbation leaves the set of point pairs in
// contact as it was (no pair crosses d = 1, where the force's derivative jumps), the
// model's error is of second order: halving the perturbation quarters it. It also captures
// nearly all of the force's change (the exact Hessian, the damping at the new velocity),
// and its energy's error is of third order. (The linearisation starts from rest: the
// damping force is taken with the normals of its point, an error of the order of the
// motion times the velocity.) Beyond reach, and after refresh(), the evaluation is exact.
TEST(ContactTerm, ReusedLinearisationIsSecondOrderAccurate) {
  Params p;
  p.solver.integrator = Integrator::IMEX_CONTACT;
  p.solver.contact_reuse = 1.0;
  const Sample s = make(knit_like_sample(2, 2, 8, 0.125, 0.8), p);
  const Model& m = s.model;
  const double r = m.params.material.radius;
  const int n = static_cast<int>(s.q.size());
  const Eigen::VectorXd v0 = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd dq = random_vector(n, 1.0, 22);
  double largest = 0;
  for (int k = 0; k < n; k += 3) largest = std::max(largest, dq.segment<3>(k).norm());
  dq /= largest;  // the largest control point's move is 1 cm
  const Eigen::VectorXd dv = random_vector(n, 1.0, 23);
  // the exact force, energy and point pairs in contact at (q0 + ε dq, v0 + ε dv)
  auto exact = [&](double eps, double& energy, std::vector<ContactPointPair>* pairs) {
    Sample moved = s;
    moved.q += eps * dq;
    ContactTerm fresh(m);
    fresh.set_record_point_pairs(true);
    const Eigen::VectorXd f = force_of(fresh, moved, v0 + eps * dv, &energy);
    if (pairs) *pairs = fresh.last_point_pairs();
    return f;
  };
  double e0 = 0;
  std::vector<ContactPointPair> pairs0;
  const Eigen::VectorXd f0 = exact(0, e0, &pairs0);
  ASSERT_GT(pairs0.size(), 50u);
  // the largest ε (a power of 2 of r) whose perturbation, and half of it, keep the pairs
  double eps = r;
  for (;; eps /= 2) {
    ASSERT_GT(eps, 1e-8 * r) << "no perturbation keeps the pairs in contact";
    std::vector<ContactPointPair> a, b;
    double unused = 0;
    exact(eps, unused, &a);
    exact(eps / 2, unused, &b);
    if (a == pairs0 && b == pairs0) break;
  }
  ContactTerm term(m);
  term.set_operator_stiffness(true);
  {
    Eigen::VectorXd f = Eigen::VectorXd::Zero(n);
    // (the kernels with the stiffness on round differently from those without)
    EXPECT_NEAR(term.add_force(m, s.q, v0, 0.0, f), e0, 1e-12 * e0);
    EXPECT_LT(max_abs(f - f0), 1e-12 * max_abs(f0)) << "its point is evaluated exactly";
    EXPECT_FALSE(term.last_stats().linearised);
  }
  double force_error[2], energy_error[2];
  for (int k = 0; k < 2; ++k) {
    const double e = eps / (1 << k);
    double energy = 0, exact_energy = 0;
    const Eigen::VectorXd want = exact(e, exact_energy, nullptr);
    Eigen::VectorXd f = Eigen::VectorXd::Zero(n);
    const Eigen::VectorXd v = v0 + e * dv;
    energy = term.add_force(m, s.q + e * dq, v, 0.0, f);
    ASSERT_TRUE(term.last_stats().linearised);
    // the stiffness at the linearisation's point: K v, formed on the way, is K (2v) / 2
    Eigen::VectorXd kv = Eigen::VectorXd::Zero(n), k2v = Eigen::VectorXd::Zero(n);
    term.add_stiffness_product(m, v, kv);
    term.add_stiffness_product(m, 2.0 * v, k2v);
    ASSERT_GT(max_abs(k2v), 0.0);
    EXPECT_LT(max_abs(kv - 0.5 * k2v), 1e-12 * max_abs(k2v));
    force_error[k] = max_abs(f - want);
    energy_error[k] = std::abs(energy - exact_energy);
    // the model captures the change: its error is a small part of it
    EXPECT_LT(force_error[k], 1e-2 * max_abs(want - f0)) << "ε = " << e / r << " r";
    EXPECT_LT(energy_error[k], 1e-2 * std::abs(exact_energy - e0)) << "ε = " << e / r << " r";
  }
  EXPECT_EQ(term.linearised_evaluations(), 2);
  EXPECT_EQ(term.evaluations(), 1);
  // the segment blocks, kept while reusing, are those of the linearisation's point (asked
  // twice: formed, then kept)
  {
    Params p0 = p;
    p0.solver.contact_reuse = 0;
    const Sample plain = make(knit_like_sample(2, 2, 8, 0.125, 0.8), p0);
    ContactTerm reference(plain.model);
    reference.set_operator_stiffness(true);
    force_of(reference, plain, v0);
    std::vector<Matrix12d> want(m.num_seg(), Matrix12d::Zero());
    reference.add_operator_segment_stiffness(plain.model, want);
    for (int pass = 0; pass < 2; ++pass) {
      std::vector<Matrix12d> blocks(m.num_seg(), Matrix12d::Zero());
      term.add_operator_segment_stiffness(m, blocks);
      double worst = 0, scale = 0;
      for (int i = 0; i < m.num_seg(); ++i) {
        worst = std::max(worst, max_abs((blocks[i] - want[i]).reshaped()));
        scale = std::max(scale, max_abs(want[i].reshaped()));
      }
      EXPECT_LT(worst, 1e-12 * scale) << "pass " << pass;
    }
  }
  const double force_order = std::log2(force_error[0] / force_error[1]);
  const double energy_order = std::log2(energy_error[0] / energy_error[1]);
  EXPECT_NEAR(force_order, 2.0, 0.3) << force_error[0] << " → " << force_error[1];
  EXPECT_NEAR(energy_order, 3.0, 0.5) << energy_error[0] << " → " << energy_error[1];
  // beyond reach (1 r): exact, and the new linearisation's point
  {
    const Eigen::VectorXd q_far = s.q + 1.5 * r * dq;
    Eigen::VectorXd f = Eigen::VectorXd::Zero(n), want = Eigen::VectorXd::Zero(n);
    term.add_force(m, q_far, v0, 0.0, f);
    EXPECT_FALSE(term.last_stats().linearised);
    ContactTerm fresh(m);
    fresh.add_force(m, q_far, v0, 0.0, want);
    EXPECT_LT(max_abs(f - want), 1e-12 * max_abs(want));
  }
  // refresh(): the next evaluation is exact even within reach
  term.refresh();
  Eigen::VectorXd f = Eigen::VectorXd::Zero(n);
  term.add_force(m, s.q + 1.5 * r * dq + 1e-3 * r * dq, v0, 0.0, f);
  EXPECT_FALSE(term.last_stats().linearised);
  EXPECT_EQ(term.evaluations(), 3);
}

// The reuse distance scales with set_reuse_scale (Simulator::set_reuse_scale): a move of
// 1.5 ρ r is beyond reach at scales 1 and 1.4, within it at 1.6 and 2.
TEST(ContactTerm, ReuseScaleWidensTheReach) {
  Params p;
  p.solver.integrator = Integrator::IMEX_CONTACT;
  p.solver.contact_reuse = 0.5;
  const Sample s = make(knit_like_sample(2, 2, 8, 0.125, 0.8), p);
  const Model& m = s.model;
  const double reach = 0.5 * m.params.material.radius;
  const int n = static_cast<int>(s.q.size());
  const Eigen::VectorXd v0 = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd dq = random_vector(n, 1.0, 31);
  double largest = 0;
  for (int k = 0; k < n; k += 3) largest = std::max(largest, dq.segment<3>(k).norm());
  dq *= 1.5 * reach / largest;  // the largest control point's move is 1.5 ρ r
  auto linearised = [&](double scale) {
    ContactTerm term(m);
    term.set_operator_stiffness(true);
    term.set_reuse_scale(scale);
    Eigen::VectorXd f = Eigen::VectorXd::Zero(n);
    term.add_force(m, s.q, v0, 0.0, f);
    EXPECT_FALSE(term.last_stats().linearised);
    term.add_force(m, s.q + dq, v0, 0.0, f);
    return term.last_stats().linearised;
  };
  EXPECT_FALSE(linearised(1.0));
  EXPECT_TRUE(linearised(2.0));
  EXPECT_FALSE(linearised(1.4));
  EXPECT_TRUE(linearised(1.6));
}

// Reuse needs the stiffness that only the imex-contact integrator keeps.
TEST(ContactTerm, ReuseRejectsIntegratorsWithoutTheContactStiffness) {
  Params p;
  p.solver.contact_reuse = 0.05;
  p.solver.integrator = Integrator::IMEX;
  EXPECT_THROW(validate_params(p), std::invalid_argument);
  p.solver.integrator = Integrator::IMEX_CONTACT;
  EXPECT_NO_THROW(validate_params(p));
}

}  // namespace
}  // namespace knit
