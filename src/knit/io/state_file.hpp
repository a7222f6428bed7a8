#pragma once
// knitsim's native state file (.kstate): exact (binary float64) positions and
// velocities, the yarn layout and radii, and optional stitch coordinates, so a state can
// be rendered or exported without its scene. Versioned; written atomically.
//
// Layout (little-endian):
//   "KNITSTAT" | u32 version (=1) | u32 num_yarns | u32 flags (bit 0: stitches) | f64 time
//   per yarn: u32 num_cp | f64 radius (cm)
//   f64 q[3·num_cp] | f64 v[3·num_cp]
//   if stitches: per segment i32 row, i32 col
//   "KEND"
#include <string>
#include <vector>

#include "knit/model/model.hpp"
#include "knit/model/state.hpp"

namespace knit {

struct StateFile {
  State state;
  std::vector<int> yarn_cp_counts;  ///< control points per yarn
  std::vector<double> yarn_radius;  ///< cm
  std::vector<StitchCoord> stitch;  ///< per segment; empty when unknown
  int num_cp() const;
  int num_seg() const;
  /// Global index of the first control point of every yarn.
  std::vector<int> yarn_cp_begin() const;
};

inline constexpr unsigned STATE_FILE_VERSION = 1;

/// Snapshot of a model's layout with the given state.
StateFile make_state_file(const Model& model, const State& state);
/// Writes to a temporary file beside `path` and renames it, so `path` is never half-written.
void write_state_file(const std::string& path, const StateFile& file);
/// Reads and validates; throws std::runtime_error naming the file and byte offset.
StateFile read_state_file(const std::string& path);

/// Writes `contents` to `path` atomically (temporary file + rename). Throws on failure.
void write_file_atomic(const std::string& path, const std::string& contents);

}  // namespace knit
