#include "knit/filters/nonrigid_damping.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <Eigen/Dense>
#include <algorithm>
#include <random>

#include "knit/pattern/generator.hpp"

namespace knit {
namespace {

Model swatch(int rows = 4, int cols = 4) {
  KnitOptions o;
  o.rows = rows;
  o.cols = cols;
  return build_knit_model(generate_knit(builtin_pattern("stockinette"), o), Params{});
}

// The control points of swatch(rows, cols) as generated.
Eigen::VectorXd positions(int rows = 4, int cols = 4) {
  KnitOptions o;
  o.rows = rows;
  o.cols = cols;
  const GeneratedKnit g = generate_knit(builtin_pattern("stockinette"), o);
  return Eigen::Map<const Eigen::VectorXd>(g.control_points.data(), g.control_points.size());
}

Eigen::VectorXd rigid_velocity(const Eigen::VectorXd& q, const Eigen::Vector3d& vel,
                               const Eigen::Vector3d& omega) {
  Eigen::VectorXd v(q.size());
  for (int k = 0; k < q.size() / 3; ++k)
    v.segment<3>(3 * k) = vel + omega.cross(q.segment<3>(3 * k));
  return v;
}

Eigen::VectorXd random_velocity(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0, 10);
  Eigen::VectorXd v(n);
  for (int i = 0; i < n; ++i) v[i] = g(rng);
  return v;
}

RegionList everything(const Model& m) {
  RegionList r(1);
  for (int i = 0; i < m.num_seg(); ++i) r[0].push_back(i);
  return r;
}

// lumped-mass momenta of the control points
Eigen::Vector3d linear_momentum(const Model& m, const Eigen::VectorXd& v) {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int k = 0; k < m.num_cp(); ++k) p += m.mass[k] * v.segment<3>(3 * k);
  return p;
}
Eigen::Vector3d angular_momentum(const Model& m, const Eigen::VectorXd& q,
                                 const Eigen::VectorXd& v) {
  Eigen::Vector3d l = Eigen::Vector3d::Zero();
  for (int k = 0; k < m.num_cp(); ++k)
    l += m.mass[k] * q.segment<3>(3 * k).cross(v.segment<3>(3 * k));
  return l;
}

// mass-weighted squared distance of sample velocities from their best rigid fit
double nonrigid_residual(const SampleSegments& s, const Eigen::Matrix3Xd& x,
                         const Eigen::Matrix3Xd& u) {
  double mass = 0;
  Eigen::Vector3d cx = Eigen::Vector3d::Zero(), p = Eigen::Vector3d::Zero();
  for (int i = 0; i < s.num_samples(); ++i)
    mass += s.mass(i), cx += s.mass(i) * x.col(i), p += s.mass(i) * u.col(i);
  cx /= mass;
  const Eigen::Vector3d vc = p / mass;
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
  Eigen::Vector3d l = Eigen::Vector3d::Zero();
  for (int i = 0; i < s.num_samples(); ++i) {
    const Eigen::Vector3d d = x.col(i) - cx;
    l += s.mass(i) * d.cross(u.col(i) - vc);
    inertia += s.mass(i) * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
  }
  const Eigen::Vector3d w = inertia.ldlt().solve(l);
  double r = 0;
  for (int i = 0; i < s.num_samples(); ++i)
    r += s.mass(i) * (u.col(i) - vc - w.cross(x.col(i) - cx)).squaredNorm();
  return r;
}

TEST(Filter, SampleMassesMatchTheLumpedMass) {
  const Model m = swatch();
  const SampleSegments s(m, 8);
  double total = 0;
  for (double w : s.masses()) total += w;
  EXPECT_NEAR(total, m.mass.sum(), 1e-12 * m.mass.sum());
  // also after the relaxation shrink, which changes rest lengths but not masses
  const Model shrunk = scale_rest_lengths(m, 0.935);
  const SampleSegments s2(shrunk, 8);
  total = 0;
  for (double w : s2.masses()) total += w;
  EXPECT_NEAR(total, m.mass.sum(), 1e-12 * m.mass.sum());
  // a uniform Δv moves the momentum by exactly Σ m_s Δv
  Eigen::VectorXd v = Eigen::VectorXd::Zero(m.num_dof());
  Eigen::Matrix3Xd dv(3, s.num_samples());
  dv.colwise() = Eigen::Vector3d(1, -2, 3);
  s.apply(m, dv, v);
  EXPECT_LT((linear_momentum(m, v) - total * Eigen::Vector3d(1, -2, 3)).norm(), 1e-12 * total * 4);
}

TEST(Filter, RigidMotionIsLeftAlone) {
  const Model m = swatch();
  const Eigen::VectorXd q = positions();
  const Eigen::VectorXd v0 = rigid_velocity(q, {3, -1, 2}, {0.5, 2, -1});
  NonRigidDampingFilter single(m, everything(m), 1.0);
  NonRigidDampingFilter two_pass(m, 0.7, 0.4);
  for (VelocityFilter* f :
       {static_cast<VelocityFilter*>(&single), static_cast<VelocityFilter*>(&two_pass)}) {
    Eigen::VectorXd v = v0;
    f->apply(m, q, v, 0.0, 1e-4);
    EXPECT_LT((v - v0).norm(), 1e-11 * v0.norm()) << f->name();
  }
  EXPECT_EQ(two_pass.name(), "nonrigid_damping");
}

// With α = 1 and one region, the filter asks every sample for exactly the region's rigid
// velocity; the impulses then pass through the B-spline basis and the lumped mass, which
// smooth them, so the samples end much closer to rigid but not exactly, and repeating the
// filter converges to rigid motion (a fixed point: the non-rigid part keeps shrinking).
TEST(Filter, AlphaOneMakesTheMotionRigid) {
  const Model m = swatch();
  const Eigen::VectorXd q = positions();
  NonRigidDampingFilter f(m, everything(m), 1.0);
  const SampleSegments& s = f.samples();
  const Eigen::Matrix3Xd x = s.positions(m, q);
  for (const bool smooth : {true, false}) {
    Eigen::VectorXd v(m.num_dof());
    if (smooth) {  // a bending and shearing field, smooth along the yarn
      for (int k = 0; k < m.num_cp(); ++k) {
        const Eigen::Vector3d p = q.segment<3>(3 * k);
        v.segment<3>(3 * k) = Eigen::Vector3d(p.y() * p.y(), 0.5 * p.x(), p.x() * p.y());
      }
    } else {  // noise on every control point
      v = random_velocity(m.num_dof(), 7);
    }
    const double before = nonrigid_residual(s, x, s.velocities(m, v));
    f.apply(m, q, v, 0.0, 1e-4);
    const double once = nonrigid_residual(s, x, s.velocities(m, v));
    EXPECT_LT(once, (smooth ? 0.05 : 0.5) * before) << (smooth ? "smooth" : "noise");
    double last = once;
    for (int it = 0; it < 30; ++it) {
      f.apply(m, q, v, 0.0, 1e-4);
      const double now = nonrigid_residual(s, x, s.velocities(m, v));
      EXPECT_LE(now, last * (1 + 1e-12));
      last = now;
    }
    EXPECT_LT(last, 1e-3 * before) << (smooth ? "smooth" : "noise");
  }
}

// The leftover of one pass (MODEL.md §4: Δv(s) = (α / r(s)) Σ_{R ∋ s} (v_rigid,R(s) − v(s))).
// Give the samples the velocities u = w + n, w a rigid motion and n a field with no
// momentum and no angular momentum on any one segment, hence none on any region whatever the
// overlaps (a region's weights m_s / r(s) are constant along each of its segments). Every
// region's rigid fit is then w itself, so Δv = −α n: the pass leaves exactly (1 − α) n of
// the non-rigid velocity and keeps w. The first pass must do this with α_small on the small
// regions, the second with α_large on the large ones.
TEST(Filter, EachPassLeavesOneMinusAlphaOfTheNonRigidVelocity) {
  const Model m = swatch(6, 6);
  const Eigen::VectorXd q = positions(6, 6);
  const double alpha_small = 0.7, alpha_large = 0.25;
  NonRigidDampingFilter f(m, alpha_small, alpha_large);
  const SampleSegments& samples = f.samples();
  const int per = samples.samples_per_segment();
  const Eigen::Matrix3Xd x = samples.positions(m, q);
  // w: a rigid motion; n: random, projected segment by segment onto Σ n = 0, Σ x × n = 0
  const Eigen::Vector3d vel(2, -1, 0.5), omega(0.3, -0.8, 1.1);
  Eigen::Matrix3Xd w(3, x.cols()), n(3, x.cols());
  for (Eigen::Index s = 0; s < x.cols(); ++s) w.col(s) = vel + omega.cross(x.col(s));
  const Eigen::VectorXd noise = random_velocity(3 * static_cast<int>(x.cols()), 17);
  for (int i = 0; i < m.num_seg(); ++i) {
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(6, 3 * per);
    for (int k = 0; k < per; ++k) {
      const Eigen::Vector3d p = x.col(i * per + k);
      a.block<3, 3>(0, 3 * k).setIdentity();
      a.block<3, 3>(3, 3 * k) << 0, -p.z(), p.y(), p.z(), 0, -p.x(), -p.y(), p.x(), 0;
    }
    const Eigen::VectorXd r = noise.segment(3 * i * per, 3 * per);
    const Eigen::VectorXd proj = r - a.completeOrthogonalDecomposition().solve(a * r);
    ASSERT_LT((a * proj).norm(), 1e-9 * r.norm()) << "segment " << i;
    n.middleCols(i * per, per) = proj.reshaped(3, per);
  }
  const Eigen::Matrix3Xd u = w + n;
  ASSERT_EQ(f.passes().size(), 2u);
  const double expected_alpha[2] = {alpha_small, alpha_large};
  const RegionList expected_regions[2] = {small_stitch_regions(m), large_stitch_regions(m)};
  for (int p = 0; p < 2; ++p) {
    const RigidRegionPass& pass = f.passes()[p];
    EXPECT_EQ(pass.regions(), expected_regions[p]) << "pass " << p;
    Eigen::Matrix3Xd dv = Eigen::Matrix3Xd::Zero(3, x.cols());
    pass.velocity_change(samples, x, u, dv);
    const Eigen::Matrix3Xd left = u + dv - w;
    EXPECT_LT((left - (1 - expected_alpha[p]) * n).cwiseAbs().maxCoeff(),
              1e-9 * n.cwiseAbs().maxCoeff())
        << "pass " << p << " should leave " << 1 - expected_alpha[p]
        << " of the non-rigid velocity";
  }
}

// α is a strength per reference step (FILTER_REFERENCE_STEP = 1/11800 s): the same damping
// per unit of time at any step. A pass at step h leaves (1 − α)^(h / h_ref) of the
// non-rigid velocity, so two steps of h/2 leave what one step of h does; at h_ref it is α.
TEST(Filter, DampingIsARatePerUnitTime) {
  const double ref = FILTER_REFERENCE_STEP;
  EXPECT_EQ(per_step_strength(0.3, ref), 0.3);
  EXPECT_EQ(per_step_strength(0.3, 0.0), 0.3);
  EXPECT_EQ(per_step_strength(1.0, 4 * ref), 1.0);
  EXPECT_EQ(per_step_strength(0.0, 4 * ref), 0.0);
  for (double alpha : {0.1, 0.3, 0.675})
    for (double h : {ref / 3, ref, 2.5 * ref, 7 * ref}) {
      const double half = per_step_strength(alpha, h / 2), whole = per_step_strength(alpha, h);
      EXPECT_NEAR((1 - half) * (1 - half), 1 - whole, 1e-14) << alpha << " " << h;
      EXPECT_GT(whole, half);
    }
  EXPECT_NEAR(per_step_strength(0.3, 2 * ref), 1 - 0.7 * 0.7, 1e-15);
  // the whole filter on a swatch: one step of 2 h_ref and two of h_ref damp alike (within
  // the spline's smoothing of the impulses), where α per step would damp twice as much
  const Model m = swatch();
  const Eigen::VectorXd q = positions();
  NonRigidDampingFilter f(m, 0.3, 0.3);
  const SampleSegments& s = f.samples();
  const Eigen::Matrix3Xd x = s.positions(m, q);
  const Eigen::VectorXd v0 = random_velocity(m.num_dof(), 23);
  Eigen::VectorXd one = v0, two = v0;
  f.apply(m, q, one, 0.0, 2 * ref);
  f.apply(m, q, two, 0.0, ref);
  f.apply(m, q, two, 0.0, ref);
  const double before = nonrigid_residual(s, x, s.velocities(m, v0));
  const double r1 = nonrigid_residual(s, x, s.velocities(m, one));
  const double r2 = nonrigid_residual(s, x, s.velocities(m, two));
  EXPECT_LT(r1, 0.9 * before);
  EXPECT_NEAR(r1, r2, 0.1 * (before - r2)) << "before " << before;
}

// Which pass damps what (MODEL.md §4). A small region is a stitch and the one below it,
// so it lies in one column; the large regions (blocks of 4 × 4 stitches) span columns.
// Columns sliding past each other along the wale (each column moving as a whole, neighbours
// in opposite directions) are a rigid motion of every small region but not of the large
// ones: the small pass must leave such motion nearly alone (only the spline's blending at
// the column boundaries shows it) and the large pass must damp it.
TEST(Filter, SmallRegionsLetColumnsSlideLargeRegionsDampIt) {
  const Model m = swatch(8, 8);
  const Eigen::VectorXd q = positions(8, 8);
  Eigen::VectorXd sliding(m.num_dof());
  for (int c = 0; c < m.num_cp(); ++c) {
    const int seg = std::clamp(c - 2, 0, m.num_seg() - 1);  // a segment the point shapes
    sliding.segment<3>(3 * c) = Eigen::Vector3d(0, m.stitch[seg].col % 2 ? 5.0 : -5.0, 0);
  }
  // the share of the sliding motion a filter keeps: mass-weighted projection onto it
  auto kept = [&](VelocityFilter& f) {
    Eigen::VectorXd v = sliding;
    f.apply(m, q, v, 0.0, 1e-4);
    double num = 0, den = 0;
    for (int c = 0; c < m.num_cp(); ++c) {
      num += m.mass[c] * v.segment<3>(3 * c).dot(sliding.segment<3>(3 * c));
      den += m.mass[c] * sliding.segment<3>(3 * c).squaredNorm();
    }
    return num / den;
  };
  NonRigidDampingFilter small_only(m, small_stitch_regions(m), 0.8);
  NonRigidDampingFilter large_only(m, large_stitch_regions(m), 0.8);
  // measured: the small pass alone (α = 0.8) keeps 0.914 of the sliding, the large pass
  // alone (α = 0.8) 0.413; the filter with α_small = 0.8, α_large = 0.2 keeps 0.782, with
  // the strengths the other way round 0.406. Allowed: > 0.87, < 0.5, > 0.7.
  EXPECT_GT(kept(small_only), 0.87);
  EXPECT_LT(kept(large_only), 0.5);
  NonRigidDampingFilter filter(m, 0.8, 0.2);
  EXPECT_GT(kept(filter), 0.7) << "the large regions' α_large = 0.2 should act on the sliding, "
                                  "not the small regions' α_small = 0.8";
}

TEST(Filter, MomentumIsConservedForAnyAlphaAndOverlap) {
  const Model m = swatch(5, 6);
  const Eigen::VectorXd q = positions(5, 6);
  const Eigen::VectorXd v0 = random_velocity(m.num_dof(), 11);
  const Eigen::Vector3d p0 = linear_momentum(m, v0), l0 = angular_momentum(m, q, v0);
  const double p_scale = linear_momentum(m, v0.cwiseAbs()).norm();
  const double l_scale = p_scale * q.cwiseAbs().maxCoeff();
  NonRigidDampingFilter one(m, everything(m), 0.37);
  NonRigidDampingFilter overlapping(m, 0.65, 0.3);
  NonRigidDampingFilter small_only(m, small_stitch_regions(m), 0.8);
  for (VelocityFilter* f :
       {static_cast<VelocityFilter*>(&one), static_cast<VelocityFilter*>(&overlapping),
        static_cast<VelocityFilter*>(&small_only)}) {
    Eigen::VectorXd v = v0;
    f->apply(m, q, v, 0.0, 1e-4);
    EXPECT_GT((v - v0).norm(), 1e-3 * v0.norm());  // it did something
    EXPECT_LT((linear_momentum(m, v) - p0).norm(), 1e-12 * p_scale);
    EXPECT_LT((angular_momentum(m, q, v) - l0).norm(), 1e-12 * l_scale);
  }
}

TEST(Filter, RegionsFromStitchCoordinates) {
  const Model m = swatch(6, 6);
  const RegionList small = small_stitch_regions(m);
  EXPECT_EQ(small.size(), 36u);  // one per stitch
  // every stitch segment is in its own region and in the region of the stitch above
  std::vector<int> count(m.num_seg(), 0);
  for (const auto& r : small)
    for (int i : r) ++count[i];
  for (int i = 0; i < m.num_seg(); ++i)
    EXPECT_EQ(count[i], m.stitch[i].row == 5 ? 1 : 2) << "segment " << i;
  // large 4×4 blocks every 2 stitches: each stitch in 2 × 2 blocks
  const RegionList large = large_stitch_regions(m);
  EXPECT_EQ(large.size(), 16u);
  count.assign(m.num_seg(), 0);
  for (const auto& r : large)
    for (int i : r) ++count[i];
  for (int i = 0; i < m.num_seg(); ++i) EXPECT_EQ(count[i], 4) << "segment " << i;
  // around a tube the blocks wrap past the seam: 3 block columns (not 4), each whole, and
  // still 2 × 2 blocks on every stitch; a block at the seam joins the last and first columns
  const RegionList wrapped = large_stitch_regions(m, 4, 2, true);
  EXPECT_EQ(wrapped.size(), 12u);
  count.assign(m.num_seg(), 0);
  bool seam = false;
  for (const auto& r : wrapped) {
    bool first = false, last = false;
    for (int i : r) {
      ++count[i];
      first |= m.stitch[i].col == 0;
      last |= m.stitch[i].col == 5;
    }
    seam |= first && last;
  }
  for (int i = 0; i < m.num_seg(); ++i) EXPECT_EQ(count[i], 4) << "segment " << i;
  EXPECT_TRUE(seam);
}

TEST(Filter, SegmentsWithoutStitchesAreUntouched) {
  ModelBuilder b;
  Eigen::Matrix3Xd cp(3, 12);
  for (int k = 0; k < 12; ++k) cp.col(k) = Eigen::Vector3d(k, 0.1 * k * k, 0);
  b.add_yarn(cp);
  const Model m = b.build(Params{});
  const Eigen::VectorXd q = Eigen::Map<const Eigen::VectorXd>(cp.data(), cp.size());
  NonRigidDampingFilter f(m, 0.7, 0.3);
  Eigen::VectorXd v = random_velocity(m.num_dof(), 3);
  const Eigen::VectorXd v0 = v;
  f.apply(m, q, v, 0.0, 1e-4);
  EXPECT_EQ(v, v0);
  EXPECT_THROW(NonRigidDampingFilter(m, RegionList{{0, 99}}, 0.5), std::out_of_range);
  EXPECT_THROW(NonRigidDampingFilter(m, RegionList{{0}}, 1.5), std::invalid_argument);
}

TEST(Filter, ResultDoesNotDependOnThreadCount) {
  const Model m = swatch(4, 6);
  const Eigen::VectorXd q = positions(4, 6);
  NonRigidDampingFilter f(m, 0.6, 0.3);
  Eigen::VectorXd a = random_velocity(m.num_dof(), 5), b = a;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    f.apply(m, q, a, 0.0, 1e-4);
  }
  f.apply(m, q, b, 0.0, 1e-4);
  EXPECT_EQ(a, b);
}

}  // namespace
}  // namespace knit
