#include "knit/spline/basis.hpp"

#include <gtest/gtest.h>

namespace knit {
namespace {

TEST(Basis, PartitionOfUnity) {
  for (double t = 0; t <= 1.0; t += 0.05) {
    EXPECT_NEAR(bspline_basis(t).sum(), 1.0, 1e-14) << "t=" << t;
    EXPECT_NEAR(bspline_basis_d1(t).sum(), 0.0, 1e-14) << "t=" << t;
    EXPECT_NEAR(bspline_basis_d2(t).sum(), 0.0, 1e-14) << "t=" << t;
  }
}

}  // namespace
}  // namespace knit
