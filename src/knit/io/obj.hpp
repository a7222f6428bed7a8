#pragma once
// Wavefront OBJ, read by one parser: `v x y z [w]` vertices, `l i j k …` line elements and
// `f i j k …` faces (1-based indices, negative ones relative to the vertices read so far,
// `i/t/n` accepted; every other statement — normals, groups, materials, comments — is
// ignored). Yarn polylines (import.hpp, parse_obj) are its line elements, object meshes
// its faces. Malformed input raises std::runtime_error naming the file, line and byte.
#include <Eigen/Core>
#include <string>
#include <string_view>
#include <vector>

#include "knit/objects/mesh_shape.hpp"

namespace knit {

/// An OBJ file's geometry, indices resolved (0-based).
struct ObjGeometry {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::vector<long long>> lines;  ///< each `l` element's vertices
  std::vector<std::vector<long long>> faces;  ///< each `f` element's corners
};

/// Parses an OBJ file's bytes; `name` is used in error messages.
ObjGeometry parse_obj_geometry(std::string_view data, const std::string& name);

/// The faces of the OBJ file at `path` as triangles (a face with more than three corners
/// split around its first), coordinates multiplied by `scale`. Throws std::runtime_error
/// naming the file (and line) for a malformed statement, an index out of range, or a file
/// without faces.
TriangleMesh read_obj_mesh(const std::string& path, double scale = 1.0);

/// Writes `mesh` as a Wavefront OBJ (`v` and `f` lines) atomically.
void write_obj_mesh(const TriangleMesh& mesh, const std::string& path);

}  // namespace knit
