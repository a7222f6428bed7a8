#include "knit/contact/contact_samples.hpp"

#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

#include "knit/spline/fit.hpp"

namespace knit {

ModelBuilder knit_like_sample(int rows, int loops_per_row, int segments_per_loop, double radius,
                              double squeeze) {
  if (rows < 1 || loops_per_row < 1 || segments_per_loop < 1)
    throw std::invalid_argument("knit_like_sample: rows, loops and segments must be positive");
  constexpr double A = 1.5, H = 4.0, D = 1.0, TUBE = 0.8;
  const double scale = squeeze * radius / TUBE;
  const int samples_per_loop = 16 * segments_per_loop;
  const int n = loops_per_row * samples_per_loop + 1;
  ModelBuilder builder;
  for (int row = 0; row < rows; ++row) {
    Eigen::Matrix3Xd curve(3, n);
    for (int k = 0; k < n; ++k) {
      const double t = 2 * std::numbers::pi * k / samples_per_loop;
      curve.col(k) =
          scale * Eigen::Vector3d(t + A * std::sin(2 * t), H * std::cos(t) + (H + 0.5) * row,
                                  D * std::cos(2 * t));
    }
    builder.add_yarn(fit_polyline(curve, loops_per_row * segments_per_loop));
  }
  return builder;
}

ModelBuilder random_tangle(int yarns, int segments, double box, std::uint32_t seed, double step,
                           double turn) {
  if (yarns < 1 || segments < 1)
    throw std::invalid_argument("random_tangle: yarns and segments must be positive");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  auto random_unit = [&] {
    Eigen::Vector3d d;
    do d = Eigen::Vector3d(uni(rng), uni(rng), uni(rng));
    while (d.squaredNorm() > 1.0 || d.squaredNorm() < 1e-4);
    return d.normalized();
  };
  const double half = 0.5 * box;
  ModelBuilder builder;
  for (int y = 0; y < yarns; ++y) {
    Eigen::Matrix3Xd cp(3, segments + 3);
    Eigen::Vector3d p(uni(rng) * half, uni(rng) * half, uni(rng) * half);
    Eigen::Vector3d dir = random_unit();
    for (int k = 0; k < cp.cols(); ++k) {
      cp.col(k) = p;
      // turn by a bounded random angle, bounce off the walls of the cube
      dir = (dir + std::tan(0.5 * turn) * random_unit()).normalized();
      for (int c = 0; c < 3; ++c)
        if (std::abs(p[c] + step * dir[c]) > half) dir[c] = -dir[c];
      p += step * dir;
    }
    builder.add_yarn(cp);
  }
  return builder;
}

}  // namespace knit
