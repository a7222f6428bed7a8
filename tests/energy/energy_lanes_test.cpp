// The lane kernels (four segments at once) against the plain per-segment kernels they
// replaced in the assembled terms: same energies and gradients up to round-off, on varied
// segments including the degenerate ones (straight yarn, coincident control points).
#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <string>

#include "fd_check.hpp"
#include "knit/contact/contact_samples.hpp"
#include "knit/energy/bending.hpp"
#include "knit/energy/length.hpp"

namespace knit {
namespace {

constexpr size_t COINCIDENT = 10;  // index of the segment with coincident control points

std::vector<Vector12d> varied_segments() {
  std::vector<Vector12d> segs;
  for (unsigned seed = 1; seed <= 9; ++seed)
    segs.push_back(test::jitter(Vector12d::Zero(), 0.4, seed));
  Vector12d straight, coincident, partly;
  for (int a = 0; a < 4; ++a) {
    straight.segment<3>(3 * a) = Eigen::Vector3d(0.3 * a, 0.1 * a, -0.05 * a);
    coincident.segment<3>(3 * a) = Eigen::Vector3d(0.2, -0.1, 0.3);
    partly.segment<3>(3 * a) = Eigen::Vector3d(a < 2 ? 0.0 : 0.4, 0.1, 0.0);
  }
  segs.push_back(straight);
  segs.push_back(coincident);
  segs.push_back(partly);
  return segs;  // 12 segments: three full groups of four
}

// largest |entry| (a plain loop: GCC 12 warns falsely inside Eigen's AVX-512 max reduction)
template <class V>
double max_abs(const V& v) {
  double m = 0;
  for (Eigen::Index k = 0; k < v.size(); ++k) m = std::max(m, std::abs(v[k]));
  return m;
}

// Tolerances: 1e-13 of the segment's own gradient, plus 1e-11 of the largest over all
// segments. At the segment with four coincident control points y' is round-off noise,
// and so is the direction of the gradient (bending: tiny noise amplified by 1/|y'|⁶; length:
// y'/|y'| of noise, bounded by 2 k_len Σ w |B'| / ℓ): there both kernels need only be finite.
template <class Plain, class Lanes>
void expect_lanes_match_plain(Plain plain, Lanes lane_kernel, const std::string& what) {
  using lanes::LANES;
  using lanes::VecD;
  const QuadratureTable quad = simpson_table(11);
  const std::vector<Vector12d> segs = varied_segments();
  double e_scale = 0, g_scale = 0;
  for (const Vector12d& x : segs) {
    Vector12d g = Vector12d::Zero();
    e_scale = std::max(e_scale, std::abs(plain(x, 0.3, quad, &g)));
    g_scale = std::max(g_scale, max_abs(g));
  }
  ASSERT_GT(g_scale, 0) << what;
  for (size_t first = 0; first < segs.size(); first += LANES) {
    VecD x[12], grad[12], rest;
    for (int l = 0; l < LANES; ++l) {
      for (int c = 0; c < 12; ++c) x[c][l] = segs[first + l][c];
      rest[l] = 0.3 + 0.05 * l;
    }
    const VecD energy = lane_kernel(x, rest, quad, grad);
    for (int l = 0; l < LANES; ++l) {
      Vector12d g = Vector12d::Zero();
      const double e = plain(segs[first + l], rest[l], quad, &g);
      const std::string name = what + ", segment " + std::to_string(first + l);
      if (first + l == COINCIDENT) {
        EXPECT_TRUE(std::isfinite(energy[l])) << name;
        for (int c = 0; c < 12; ++c) EXPECT_TRUE(std::isfinite(grad[c][l])) << name;
        continue;
      }
      EXPECT_NEAR(energy[l], e, 1e-13 * e_scale) << name;
      const double tol = 1e-13 * max_abs(g) + 1e-11 * g_scale;
      for (int c = 0; c < 12; ++c) EXPECT_NEAR(grad[c][l], g[c], tol) << name << ", entry " << c;
    }
  }
}

TEST(EnergyLanes, BendingLanesMatchPlainKernel) {
  expect_lanes_match_plain([](const Vector12d& x, double l, const QuadratureTable& q,
                              Vector12d* g) { return bending_kernel(x, l, 5.0, q, g); },
                           [](const lanes::VecD* x, lanes::VecD l, const QuadratureTable& q,
                              lanes::VecD* g) { return bending_kernel_lanes(x, l, 5.0, q, g); },
                           "bending");
}

TEST(EnergyLanes, LengthLanesMatchPlainKernel) {
  expect_lanes_match_plain([](const Vector12d& x, double l, const QuadratureTable& q,
                              Vector12d* g) { return length_kernel(x, l, 2000.0, q, g); },
                           [](const lanes::VecD* x, lanes::VecD l, const QuadratureTable& q,
                              lanes::VecD* g) { return length_kernel_lanes(x, l, 2000.0, q, g); },
                           "length");
}

// two yarns, 11 and 3 segments: 14 in all, in groups of four lanes 4, 4, 4 and a partial 2
ModelBuilder two_wavy_yarns() {
  Eigen::Matrix3Xd cp(3, 14);
  for (int k = 0; k < 14; ++k)
    cp.col(k) = Eigen::Vector3d(0.3 * k, 0.2 * std::sin(0.9 * k), 0.1 * std::cos(1.3 * k));
  ModelBuilder b;
  b.add_yarn(cp);
  b.add_yarn(cp.leftCols(6).colwise() + Eigen::Vector3d(0, 1, 0));
  return b;
}

// the assembled terms (lane kernels, a partial last group of four) against a plain
// per-segment assembly with the scalar kernels
TEST(EnergyLanes, AssembledTermsMatchPlainAssembly) {
  ModelBuilder b = two_wavy_yarns();
  const Model m = b.build(Params{}, 0.95);
  const Eigen::VectorXd q = test::jitter(b.positions(), 0.02, 8);
  const Eigen::VectorXd v = Eigen::VectorXd::Zero(q.size());
  for (const bool bending : {true, false}) {
    Eigen::VectorXd f = Eigen::VectorXd::Zero(q.size()), plain = f;
    const double e = bending ? BendingEnergy().add_force(m, q, v, 0.0, f)
                             : LengthEnergy().add_force(m, q, v, 0.0, f);
    double e_plain = 0;
    for (int i = 0; i < m.num_seg(); ++i) {
      Vector12d g = Vector12d::Zero();
      const Vector12d x = gather_segment(q, m.seg_cp[i]);
      e_plain += bending ? bending_kernel(x, m.rest_length[i], m.params.material.k_bend, m.quad, &g)
                         : length_kernel(x, m.rest_length[i], m.params.material.k_len, m.quad, &g);
      plain.segment<12>(3 * m.seg_cp[i]) -= g;
    }
    const char* what = bending ? "bending" : "length";
    EXPECT_NEAR(e, e_plain, 1e-12 * std::abs(e_plain)) << what;
    const double scale = max_abs(plain);
    ASSERT_GT(scale, 0) << what;
    for (Eigen::Index k = 0; k < q.size(); ++k)
      EXPECT_NEAR(f[k], plain[k], 1e-12 * scale) << what << ", coordinate " << k;
  }
}

// the length term's stiffness blocks (four segments per lane kernel, a partial last group)
// against length_hessian per segment; and the same with 1 and 2 threads, bit for bit
TEST(EnergyLanes, LengthStiffnessBlocksMatchThePlainHessian) {
  ModelBuilder b = two_wavy_yarns();
  const Model m = b.build(Params{}, 0.95);
  // stretched and compressed segments both: the projection drops only the compressed
  // ones' transverse part
  const Eigen::VectorXd q = test::jitter(b.positions(), 0.05, 8);
  auto blocks_with = [&](int threads) {
    tbb::global_control control(tbb::global_control::max_allowed_parallelism, threads);
    std::vector<Matrix12d> blocks;
    tbb::task_arena(threads).execute([&] { LengthEnergy().segment_stiffness(m, q, blocks); });
    return blocks;
  };
  const std::vector<Matrix12d> blocks = blocks_with(2), one = blocks_with(1);
  ASSERT_EQ(static_cast<int>(blocks.size()), m.num_seg());
  for (int i = 0; i < m.num_seg(); ++i) {
    const Matrix12d want =
        length_hessian(gather_segment(q, m.seg_cp[i]), m.rest_length[i], m.params.material.k_len,
                       m.quad, LengthHessian::PROJECTED);
    EXPECT_LE((blocks[i] - want).cwiseAbs().maxCoeff(), 1e-12 * want.cwiseAbs().maxCoeff())
        << "segment " << i;
    EXPECT_TRUE(blocks[i] == one[i]) << "segment " << i << ": 1 and 2 threads differ";
  }
}

// the assembled terms are bitwise independent of the thread count (per-segment slots, a
// fixed summation order)
TEST(EnergyLanes, AssembledTermsDoNotDependOnThreadCount) {
  const ModelBuilder b = knit_like_sample(4, 4, 8, 0.125, 0.9);
  const Model m = b.build(Params{});
  const Eigen::VectorXd q = test::jitter(b.positions(), 0.01, 4);
  const Eigen::VectorXd v = Eigen::VectorXd::Zero(q.size());
  // an explicit arena: a global_control alone does not raise the concurrency of the
  // thread's implicit arena after its first use
  auto forces = [&](int threads) {
    tbb::global_control control(tbb::global_control::max_allowed_parallelism, threads);
    Eigen::VectorXd f = Eigen::VectorXd::Zero(q.size());
    double e = 0;
    tbb::task_arena(threads).execute([&] {
      e = BendingEnergy().add_force(m, q, v, 0.0, f) + LengthEnergy().add_force(m, q, v, 0.0, f);
    });
    return std::make_pair(e, f);
  };
  const auto [e1, f1] = forces(1);
  const auto [e2, f2] = forces(2);
  EXPECT_EQ(e1, e2);
  ASSERT_GT(max_abs(f1), 0);
  for (Eigen::Index k = 0; k < q.size(); ++k) ASSERT_EQ(f1[k], f2[k]) << "coordinate " << k;
}

}  // namespace
}  // namespace knit
