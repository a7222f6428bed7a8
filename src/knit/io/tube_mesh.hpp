#pragma once
// Yarn as surfaces, for viewers without curve support (three.js, game engines, mesh
// tools): each yarn's tube of radius r around its exact centreline, as triangles with
// normals, closed by a flat cap at each end.
//
//   OBJ mesh  `v`, `vn`, `f a//a …` per yarn object, units cm, Z up (as the OBJ polylines)
//   PLY mesh  binary: vertex x y z nx ny nz (float) and yarn (int), face vertex_indices
//   glTF      binary .glb: one mesh per yarn (POSITION, NORMAL, uint32 indices), in glTF's
//             convention: metres, +Y up (knitsim's +Z becomes +Y, its +Y becomes −Z)
#include <Eigen/Core>
#include <string>
#include <vector>

#include "knit/io/state_file.hpp"

namespace knit {

/// Sides of the tube's cross-section unless told otherwise.
inline constexpr int TUBE_SIDES = 12;

struct TubeMesh {
  std::vector<Eigen::Vector3f> positions;  ///< cm
  std::vector<Eigen::Vector3f> normals;    ///< unit, outward
  std::vector<Eigen::Vector3i> triangles;  ///< counter-clockwise seen from outside
  /// per yarn, its vertices [vertex_begin[y], vertex_begin[y + 1]) and triangles
  /// [triangle_begin[y], triangle_begin[y + 1])
  std::vector<int> vertex_begin, triangle_begin;
  int num_yarns() const { return static_cast<int>(vertex_begin.size()) - 1; }
};

/// The tubes around every yarn's centreline sampled at `per_segment` points per segment,
/// with `sides` vertices around (a ring per sample, oriented by parallel transport so it
/// does not twist), and a cap of `sides` triangles at each end (its own vertices, with the
/// axis as normal). Each tube is closed and outward. Throws std::invalid_argument for
/// sides < 3 or per_segment < 1.
TubeMesh tube_mesh(const StateFile& state, int per_segment, int sides = TUBE_SIDES);

std::string obj_mesh_text(const TubeMesh& mesh);
std::string ply_mesh_bytes(const TubeMesh& mesh);
/// glTF 2.0 binary (metres, +Y up; see above). Throws std::runtime_error when it cannot be
/// written.
std::string glb_bytes(const TubeMesh& mesh);

}  // namespace knit
