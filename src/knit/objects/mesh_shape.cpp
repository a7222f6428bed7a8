#include "knit/objects/mesh_shape.hpp"

#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <openvdb/tools/VolumeToMesh.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

#include "knit/model/params.hpp"

namespace knit {

namespace {

void init_openvdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

class MeshShape : public Shape {
 public:
  MeshShape(openvdb::FloatGrid::Ptr grid, Eigen::AlignedBox3d box)
      : m_grid(std::move(grid)),
        m_voxel(m_grid->voxelSize()[0]),
        m_box(box),
        m_background(m_grid->background()) {}
  std::string_view kind() const override { return "mesh"; }
  double distance(const Eigen::Vector3d& x, Eigen::Vector3d* grad) const override {
    // far from the grid's bounding box: the background (a lower bound of the distance)
    if (m_box.exteriorDistance(x) > 0) {
      if (grad) *grad = Eigen::Vector3d::Zero();
      return m_background;
    }
    const Eigen::Vector3d u = x / m_voxel;  // index space: voxel centres at integers
    const Eigen::Vector3d fl = u.array().floor();
    const Eigen::Vector3d f = u - fl;
    const openvdb::Coord c0(static_cast<int>(fl[0]), static_cast<int>(fl[1]),
                            static_cast<int>(fl[2]));
    openvdb::tree::ValueAccessor<const openvdb::FloatTree, false> acc(m_grid->tree());
    double v[2][2][2];
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2; ++j)
        for (int k = 0; k < 2; ++k) v[i][j][k] = acc.getValue(c0.offsetBy(i, j, k));
    // trilinear interpolation and its exact gradient
    const double x0 = 1 - f[0], y0 = 1 - f[1], z0 = 1 - f[2];
    auto lerp_yz = [&](int i) {
      return y0 * (z0 * v[i][0][0] + f[2] * v[i][0][1]) +
             f[1] * (z0 * v[i][1][0] + f[2] * v[i][1][1]);
    };
    const double a0 = lerp_yz(0), a1 = lerp_yz(1);
    const double phi = x0 * a0 + f[0] * a1;
    if (grad) {
      auto dy = [&](int i) {
        return (z0 * v[i][1][0] + f[2] * v[i][1][1]) - (z0 * v[i][0][0] + f[2] * v[i][0][1]);
      };
      auto dz = [&](int i) {
        return y0 * (v[i][0][1] - v[i][0][0]) + f[1] * (v[i][1][1] - v[i][1][0]);
      };
      *grad =
          Eigen::Vector3d(a1 - a0, x0 * dy(0) + f[0] * dy(1), x0 * dz(0) + f[0] * dz(1)) / m_voxel;
    }
    return phi;
  }
  Eigen::AlignedBox3d bounds() const override { return m_box; }

 private:
  openvdb::FloatGrid::Ptr m_grid;
  double m_voxel;
  Eigen::AlignedBox3d m_box;
  double m_background;
};

}  // namespace

long long open_edges(const TriangleMesh& mesh) {
  std::unordered_map<unsigned long long, int> count;
  count.reserve(mesh.triangles.size() * 3);
  for (const Eigen::Vector3i& t : mesh.triangles)
    for (int e = 0; e < 3; ++e) {
      const unsigned long long a = static_cast<unsigned>(t[e]),
                               b = static_cast<unsigned>(t[(e + 1) % 3]);
      ++count[std::min(a, b) << 32 | std::max(a, b)];
    }
  long long open = 0;
  for (const auto& [edge, n] : count) open += n != 2;
  return open;
}

ShapePtr make_mesh_shape(const TriangleMesh& mesh, const MeshGridOptions& o,
                         const std::string& source) {
  if (mesh.triangles.empty()) throw std::invalid_argument(source + ": the mesh has no triangles");
  const long long open = open_edges(mesh);
  if (open > 0)
    throw std::invalid_argument(
        source + ": the mesh is not closed (" + std::to_string(open) +
        " edges are not shared by exactly two triangles), so it has no inside; close its "
        "holes in a modelling tool");
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3d& v : mesh.vertices) box.extend(v);
  const double diag = box.diagonal().norm();
  const double voxel = o.voxel_size > 0 ? o.voxel_size : std::max(0.05, diag / 256);
  const double ex = std::max(o.exterior_band, 3 * voxel), in = std::max(o.interior_band, 3 * voxel);
  // narrow-band voxels ≈ surface area / voxel² × band voxels; bound the area by the box's
  const Eigen::Vector3d d = box.diagonal();
  const double area = 2 * (d[0] * d[1] + d[1] * d[2] + d[2] * d[0]);
  const double estimate = area / (voxel * voxel) * (ex + in) / voxel;
  if (estimate > 6e7)
    throw std::invalid_argument(source + ": a distance grid of " + short_number(voxel) +
                                " cm voxels around this mesh would hold about " +
                                short_number(estimate) +
                                " voxels (at most 6e+07); give a larger voxel_size");
  init_openvdb();
  std::vector<openvdb::Vec3s> points;
  points.reserve(mesh.vertices.size());
  for (const Eigen::Vector3d& v : mesh.vertices)
    points.emplace_back(static_cast<float>(v[0]), static_cast<float>(v[1]),
                        static_cast<float>(v[2]));
  std::vector<openvdb::Vec3I> tris;
  tris.reserve(mesh.triangles.size());
  for (const Eigen::Vector3i& t : mesh.triangles)
    tris.emplace_back(static_cast<unsigned>(t[0]), static_cast<unsigned>(t[1]),
                      static_cast<unsigned>(t[2]));
  const std::vector<openvdb::Vec4I> quads;
  auto xf = openvdb::math::Transform::createLinearTransform(voxel);
  openvdb::FloatGrid::Ptr grid = openvdb::tools::meshToSignedDistanceField<openvdb::FloatGrid>(
      *xf, points, tris, quads, static_cast<float>(ex / voxel), static_cast<float>(in / voxel));
  box.min().array() -= ex;
  box.max().array() += ex;
  return std::make_shared<MeshShape>(grid, box);
}

TriangleMesh surface_mesh(const Shape& shape, const Eigen::AlignedBox3d& region_in, double voxel) {
  TriangleMesh out;
  const Eigen::AlignedBox3d inside = region_in.intersection(shape.bounds());
  if (inside.isEmpty() || !inside.diagonal().allFinite()) return out;
  if (!(voxel > 0)) voxel = inside.diagonal().norm() / 160;
  if (!(voxel > 0)) return out;
  // two voxels beyond the shape's box, so that a bounded shape closes inside the grid
  Eigen::AlignedBox3d grown = shape.bounds();
  grown.min().array() -= 2 * voxel;
  grown.max().array() += 2 * voxel;
  const Eigen::AlignedBox3d region = region_in.intersection(grown);
  const Eigen::Vector3i lo = (region.min() / voxel).array().floor().cast<int>();
  const Eigen::Vector3i hi = (region.max() / voxel).array().ceil().cast<int>();
  const Eigen::Vector3i n = hi - lo + Eigen::Vector3i::Ones();
  if (static_cast<double>(n[0]) * n[1] * n[2] > 3e7)
    throw std::invalid_argument("surface_mesh: " + short_number(voxel) +
                                " cm voxels over the region are too many; use a larger voxel");
  const double band = 3 * voxel;
  std::vector<float> values(static_cast<size_t>(n[0]) * n[1] * n[2]);
  tbb::parallel_for(0, n[2], [&](int k) {
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        const Eigen::Vector3d x = Eigen::Vector3d(lo[0] + i, lo[1] + j, lo[2] + k) * voxel;
        values[(static_cast<size_t>(k) * n[1] + j) * n[0] + i] =
            static_cast<float>(shape.distance(x, nullptr));
      }
  });
  init_openvdb();
  openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(static_cast<float>(band));
  grid->setTransform(openvdb::math::Transform::createLinearTransform(voxel));
  grid->setGridClass(openvdb::GRID_LEVEL_SET);
  {
    auto acc = grid->getAccessor();
    for (int k = 0; k < n[2]; ++k)
      for (int j = 0; j < n[1]; ++j)
        for (int i = 0; i < n[0]; ++i) {
          const float v = values[(static_cast<size_t>(k) * n[1] + j) * n[0] + i];
          const openvdb::Coord c(lo[0] + i, lo[1] + j, lo[2] + k);
          if (std::abs(v) < band)
            acc.setValue(c, v);
          else
            acc.setValueOff(c, v < 0 ? -static_cast<float>(band) : static_cast<float>(band));
        }
  }
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> tris;
  std::vector<openvdb::Vec4I> quads;
  openvdb::tools::volumeToMesh(*grid, points, tris, quads, 0.0, 0.0);
  out.vertices.reserve(points.size());
  for (const openvdb::Vec3s& p : points) out.vertices.emplace_back(p[0], p[1], p[2]);
  // OpenVDB winds its polygons clockwise seen from outside: reverse them
  for (const openvdb::Vec3I& t : tris) out.triangles.emplace_back(t[0], t[2], t[1]);
  for (const openvdb::Vec4I& q : quads) {
    out.triangles.emplace_back(q[0], q[2], q[1]);
    out.triangles.emplace_back(q[0], q[3], q[2]);
  }
  return out;
}

TriangleMesh object_surface(const SceneObject& object, double time,
                            const Eigen::AlignedBox3d& world_region, double voxel) {
  const ObjectFrame frame(object, time);
  // the region in the object frame: the box around its 8 corners taken there
  Eigen::AlignedBox3d local;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d corner =
        world_region.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c));
    local.extend(frame.rotation().transpose() * (corner - frame.origin()));
  }
  if (!(voxel > 0)) voxel = world_region.diagonal().norm() / 160;
  TriangleMesh mesh = surface_mesh(*object.shape, local, voxel);
  for (Eigen::Vector3d& v : mesh.vertices) v = frame.to_world(v);
  return mesh;
}

}  // namespace knit
