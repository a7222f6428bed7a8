#include "knit/sheet/embedding.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace knit::sheet {

namespace {

using Eigen::Vector3d;

// uniform grid over the rest mesh; each cell lists the triangles whose bounds overlap it
struct TriangleGrid {
  Vector3d lo;
  double cell = 1;
  Eigen::Array3i dims;
  std::vector<int> start;  // CSR offsets, one per cell + 1
  std::vector<int> tris;

  Eigen::Array3i cell_of(const Vector3d& p) const {
    Eigen::Array3i c;
    for (int a = 0; a < 3; ++a) {
      const double f = std::floor((p[a] - lo[a]) / cell);
      c[a] = static_cast<int>(std::clamp(f, 0.0, static_cast<double>(dims[a] - 1)));
    }
    return c;
  }
  int index(int i, int j, int k) const { return (k * dims[1] + j) * dims[0] + i; }
};

TriangleGrid build_grid(const SheetMesh& mesh) {
  const int nt = static_cast<int>(mesh.triangles.size());
  TriangleGrid g;
  g.lo = mesh.rest.rowwise().minCoeff();
  const Vector3d extent = mesh.rest.rowwise().maxCoeff() - g.lo;
  double area = 0;
  for (const auto& t : mesh.triangles)
    area += 0.5 * (mesh.rest.col(t[1]) - mesh.rest.col(t[0]))
                      .cross(mesh.rest.col(t[2]) - mesh.rest.col(t[0]))
                      .norm();
  g.cell = 1.5 * std::sqrt(area / nt);
  if (!(g.cell > 0)) g.cell = std::max(extent.maxCoeff(), 1.0);
  // at most about 8 cells per triangle, whatever the mesh's shape
  for (;;) {
    for (int a = 0; a < 3; ++a)
      g.dims[a] = std::max(1, static_cast<int>(std::ceil(extent[a] / g.cell)));
    if (static_cast<double>(g.dims.cast<double>().prod()) <= 8.0 * nt + 64) break;
    g.cell *= 1.26;
  }
  const int ncell = g.dims.prod();
  std::vector<std::array<Eigen::Array3i, 2>> range(nt);
  std::vector<int> count(ncell + 1, 0);
  for (int t = 0; t < nt; ++t) {
    Vector3d lo = mesh.rest.col(mesh.triangles[t][0]), hi = lo;
    for (int k = 1; k < 3; ++k) {
      lo = lo.cwiseMin(mesh.rest.col(mesh.triangles[t][k]));
      hi = hi.cwiseMax(mesh.rest.col(mesh.triangles[t][k]));
    }
    range[t] = {g.cell_of(lo), g.cell_of(hi)};
    for (int k = range[t][0][2]; k <= range[t][1][2]; ++k)
      for (int j = range[t][0][1]; j <= range[t][1][1]; ++j)
        for (int i = range[t][0][0]; i <= range[t][1][0]; ++i) ++count[g.index(i, j, k) + 1];
  }
  for (int c = 0; c < ncell; ++c) count[c + 1] += count[c];
  g.start = count;
  g.tris.resize(count[ncell]);
  for (int t = 0; t < nt; ++t)
    for (int k = range[t][0][2]; k <= range[t][1][2]; ++k)
      for (int j = range[t][0][1]; j <= range[t][1][1]; ++j)
        for (int i = range[t][0][0]; i <= range[t][1][0]; ++i)
          g.tris[count[g.index(i, j, k)]++] = t;
  return g;
}

// nearest triangle to p: rings of cells around p's cell until no farther cell can hold a
// nearer triangle; ties go to the lower index
int nearest_triangle(const SheetMesh& mesh, const TriangleGrid& g, const Vector3d& p) {
  const Eigen::Array3i c = g.cell_of(p);
  const int max_ring = g.dims.maxCoeff();
  double best = std::numeric_limits<double>::infinity();
  int best_t = -1;
  for (int r = 0; r <= max_ring; ++r) {
    for (int k = std::max(0, c[2] - r); k <= std::min(g.dims[2] - 1, c[2] + r); ++k)
      for (int j = std::max(0, c[1] - r); j <= std::min(g.dims[1] - 1, c[1] + r); ++j)
        for (int i = std::max(0, c[0] - r); i <= std::min(g.dims[0] - 1, c[0] + r); ++i) {
          if (std::max({std::abs(i - c[0]), std::abs(j - c[1]), std::abs(k - c[2])}) != r)
            continue;  // only the ring's shell
          const int cell = g.index(i, j, k);
          for (int q = g.start[cell]; q < g.start[cell + 1]; ++q) {
            const int t = g.tris[q];
            const auto& tri = mesh.triangles[t];
            const double d2 =
                (closest_point_on_triangle(p, mesh.rest.col(tri[0]), mesh.rest.col(tri[1]),
                                           mesh.rest.col(tri[2])) -
                 p)
                    .squaredNorm();
            if (d2 < best || (d2 == best && t < best_t)) {
              best = d2;
              best_t = t;
            }
          }
        }
    // a triangle not seen yet lies wholly outside the box of rings 0..r, so it is at least
    // as far from p as that box's nearest face with cells beyond it
    double reach = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a) {
      if (c[a] - r > 0) reach = std::min(reach, p[a] - (g.lo[a] + (c[a] - r) * g.cell));
      if (c[a] + r < g.dims[a] - 1)
        reach = std::min(reach, g.lo[a] + (c[a] + r + 1) * g.cell - p[a]);
    }
    if (best_t >= 0 && (reach == std::numeric_limits<double>::infinity() || best < reach * reach))
      break;
  }
  return best_t;
}

Vector3d unit_normal(const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  const Vector3d n = (b - a).cross(c - a);
  const double len = n.norm();
  return len > 0 ? Vector3d(n / len) : Vector3d::Zero();
}

}  // namespace

Vector3d closest_point_on_triangle(const Vector3d& p, const Vector3d& a, const Vector3d& b,
                                   const Vector3d& c) {
  const Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denom = 1 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

SheetEmbedding embed_points(const SheetMesh& mesh, const Eigen::Matrix3Xd& points) {
  if (mesh.triangles.empty())
    throw std::invalid_argument("embed_points: the mesh has no triangles");
  if (!points.allFinite()) throw std::invalid_argument("embed_points: points must be finite");
  const int n = static_cast<int>(points.cols());
  SheetEmbedding e;
  e.triangle.assign(n, -1);
  e.bary.resize(3, n);
  e.offset.resize(n);
  const TriangleGrid grid = build_grid(mesh);
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 1024), [&](const tbb::blocked_range<int>& r) {
    for (int q = r.begin(); q < r.end(); ++q) {
      const Vector3d p = points.col(q);
      const int t = nearest_triangle(mesh, grid, p);
      const auto& tri = mesh.triangles[t];
      const Vector3d x0 = mesh.rest.col(tri[0]);
      const Vector3d e1 = mesh.rest.col(tri[1]) - x0, e2 = mesh.rest.col(tri[2]) - x0;
      const Vector3d d = p - x0;
      // plane projection: [e1·e1 e1·e2; e1·e2 e2·e2] (b1, b2) = (d·e1, d·e2)
      Eigen::Matrix2d m;
      m << e1.dot(e1), e1.dot(e2), e1.dot(e2), e2.dot(e2);
      const Eigen::Vector2d b12 = m.inverse() * Eigen::Vector2d(d.dot(e1), d.dot(e2));
      e.triangle[q] = t;
      e.bary.col(q) = Vector3d(1 - b12[0] - b12[1], b12[0], b12[1]);
      e.offset[q] = d.dot(unit_normal(x0, x0 + e1, x0 + e2));
    }
  });
  return e;
}

Eigen::Matrix3Xd deform(const SheetMesh& mesh, const SheetEmbedding& embedding,
                        const Eigen::VectorXd& positions) {
  if (positions.size() != mesh.num_dofs())
    throw std::invalid_argument("deform: positions has " + std::to_string(positions.size()) +
                                " entries, expected 3 per node (" +
                                std::to_string(mesh.num_dofs()) + ")");
  const int n = embedding.size();
  Eigen::Matrix3Xd out(3, n);
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 4096), [&](const tbb::blocked_range<int>& r) {
    for (int q = r.begin(); q < r.end(); ++q) {
      const auto& tri = mesh.triangles[embedding.triangle[q]];
      const Vector3d a = positions.segment<3>(3 * tri[0]), b = positions.segment<3>(3 * tri[1]),
                     c = positions.segment<3>(3 * tri[2]);
      const Vector3d w = embedding.bary.col(q);
      out.col(q) = w[0] * a + w[1] * b + w[2] * c + embedding.offset[q] * unit_normal(a, b, c);
    }
  });
  return out;
}

}  // namespace knit::sheet
