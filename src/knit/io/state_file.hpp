#pragma once
// knitsim's native state file (.kstate): exact (binary float64) positions and
// velocities, the yarn layout and radii, and optional stitch coordinates, so a state can
// be rendered or exported without its scene. Versioned; written atomically.
//
// Layout (little-endian):
//   "KNITSTAT" | u32 version (1 to 3) | u32 num_yarns | u32 flags | f64 time (s, >= 0)
//     flags: bit 0 stitches, bit 1 knit (version 2 and later)
//   per yarn: u32 num_cp | f64 radius (cm)
//   f64 q[3·num_cp] | f64 v[3·num_cp]
//   if stitches: per segment i32 row, i32 col
//   if knit: u32 n | n bytes of JSON (pattern, rows, cols, in_the_round,
//            segments_per_stitch, stitch_size_cm, shrink, bind_off, cast_on; bind_off
//            and cast_on are absent from files written before they existed and read as
//            false; "relaxation", an object with KnitRelaxSettings' fields by name and the
//            integrator by its option name, when a relaxation wrote the file)
//            f64 rest_length[num_seg] (cm)
//            u32 num_glues | per glue: i32 segment a, f64 t a, i32 segment b, f64 t b,
//                                      f64 gap[3] (cm), f64 close_time (s)
//   "KEND"
//   u32 CRC-32 (zlib) of every byte before it (version 3)
// Versions 1 (no knit block) and 2 (no checksum) are still read. Positions, velocities
// and the time must be finite; a version 3 file whose checksum does not match is refused.
#include <nlohmann/json.hpp>
#include <optional>
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
  /// A generated knit's origin, rest lengths and glues (absent for other yarns).
  std::optional<KnitInfo> knit;
  std::vector<double> rest_length;  ///< per segment when `knit` is set (cm)
  std::vector<Glue> glues;          ///< when `knit` is set
  int num_cp() const;
  int num_seg() const;
  /// Global index of the first control point of every yarn.
  std::vector<int> yarn_cp_begin() const;
};

inline constexpr unsigned STATE_FILE_VERSION = 3;

/// A relaxation's settings as the knit block writes them (by field name; the integrator by
/// its option name).
nlohmann::json to_json(const KnitRelaxSettings& settings);

/// Snapshot of a model's layout with the given state.
StateFile make_state_file(const Model& model, const State& state);
/// Writes to a temporary file beside `path` and renames it, so `path` is never half-written.
void write_state_file(const std::string& path, const StateFile& file);
/// Reads and validates; throws std::runtime_error naming the file and byte offset.
StateFile read_state_file(const std::string& path);

/// Writes `contents` to `path` atomically (temporary file + rename). Throws on failure.
void write_file_atomic(const std::string& path, const std::string& contents);

}  // namespace knit
