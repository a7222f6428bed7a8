#pragma once
// Triangle meshes as object shapes, and object shapes as triangle meshes (for rendering
// and export). Both directions go through OpenVDB level-set grids (narrow-band signed
// distance fields): a closed mesh becomes a grid with openvdb::tools::meshToSignedDistanceField,
// and any shape's φ sampled on a grid becomes triangles with openvdb::tools::volumeToMesh.
//
// A mesh shape's φ is the trilinear interpolant of the grid's values, and its gradient is
// the interpolant's exact gradient (so the penalty term's forces are the exact gradient of
// its energy). Outside the narrow band φ is the band's half width: ≥ that far outside, ≤
// minus that far inside; points deeper inside than the interior band are not pushed out.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "knit/objects/object.hpp"
#include "knit/objects/shape.hpp"

namespace knit {

/// An indexed triangle mesh (cm), triangles counter-clockwise seen from outside.
struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> triangles;
};

/// Number of edges of `mesh` that are not shared by exactly two triangles (0: closed).
long long open_edges(const TriangleMesh& mesh);

/// Sizes of a mesh's distance grid (cm).
struct MeshGridOptions {
  double voxel_size = 0;       ///< 0: the mesh's bounding-box diagonal / 256, at least 0.05
  double exterior_band = 0.6;  ///< how far outside φ is exact (at least 3 voxels)
  double interior_band = 1.0;  ///< how far inside φ is exact (at least 3 voxels)
};

/// The shape of a closed mesh. Throws std::invalid_argument naming `source` when the
/// mesh has no triangles, is not closed (a mesh with holes has no inside: close it in a
/// modelling tool), or its grid would hold more than 6·10⁷ voxels (choose a larger voxel).
ShapePtr make_mesh_shape(const TriangleMesh& mesh, const MeshGridOptions& options,
                         const std::string& source);

/// The surface φ = 0 of `shape` inside `region` (object frame, cm) as triangles, sampled
/// on a grid of `voxel` cm (0: region diagonal / 160). A shape reaching past the region
/// is closed by the region's faces (a plane becomes a slab whose top is the plane).
TriangleMesh surface_mesh(const Shape& shape, const Eigen::AlignedBox3d& region, double voxel = 0);

/// The surface of `object` at `time` in world coordinates, where it lies inside
/// `world_region` (cm; see surface_mesh), sampled with `voxel` cm (0: region diagonal / 160).
TriangleMesh object_surface(const SceneObject& object, double time,
                            const Eigen::AlignedBox3d& world_region, double voxel = 0);

}  // namespace knit
