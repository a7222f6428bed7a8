#pragma once
// Wavefront OBJ, read by one parser: `v x y z [w]` vertices, `l i j k …` line elements and
// `f i j k …` faces (1-based indices, negative ones relative to the vertices read so far,
// `i/t/n` accepted; every other statement — normals, groups, materials, comments — is
// ignored). Yarn polylines (import.hpp, parse_obj) are its line elements, object meshes
// its faces. Malformed input raises std::runtime_error naming the file, line and byte.
// Written by one writer, ObjWriter: the yarn polylines (export.hpp), the yarn tubes
// (tube_mesh.hpp) and object surfaces (write_obj_mesh) all go through it.
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

/// Writes OBJ text: a header comment, then objects (`o NAME`), each with its vertices (`v`),
/// optionally a normal per vertex (`vn`), and line elements (`l`) or triangles (`f`, `i//i`
/// when the object has normals) indexed from 0 within the object. Coordinates are written
/// as the shortest text that reads back as the same float.
class ObjWriter {
 public:
  explicit ObjWriter(std::string_view header);
  /// Starts an object: the indices of the elements that follow count from its first vertex.
  /// An empty name writes no `o` line.
  void object(std::string_view name);
  void vertex(const Eigen::Vector3d& p);
  void normal(const Eigen::Vector3d& n);
  void line(long long a, long long b);
  void triangle(long long a, long long b, long long c);
  const std::string& text() const { return m_out; }

 private:
  void append(const Eigen::Vector3d& p);
  std::string m_out;
  long long m_vertices = 0, m_normals = 0;         // written so far
  long long m_vertex_base = 0, m_normal_base = 0;  // at the object's start
};

/// Writes `mesh` as a Wavefront OBJ (`v` and `f` lines) atomically.
void write_obj_mesh(const TriangleMesh& mesh, const std::string& path);

}  // namespace knit
