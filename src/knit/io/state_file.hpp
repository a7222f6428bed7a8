#pragma once
// knitsim's native state file (.kstate): exact (binary float64) positions and
// velocities, the yarn layout and radii, and optional stitch coordinates, so a state can
// be rendered or exported without its scene. Versioned; written atomically.
//
// Layout (little-endian):
//   "KNITSTAT" | u32 version (1 to 4) | u32 num_yarns | u32 flags | f64 time (s, >= 0)
//     flags: bit 0 stitches, bit 1 knit (version 2 and later), bit 2 run (version 4)
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
//   if run: u32 n | n bytes of JSON: what the run that wrote the state had added up from
//           its start to it (RunTotals, run_totals.hpp), for a run resumed from it
//   "KEND"
//   u32 CRC-32 (zlib) of every byte before it (version 3 and later)
// A file without a run block is written as version 3, which earlier builds read too.
// Versions 1 (no knit block) and 2 (no checksum) are still read. Positions, velocities
// and the time must be finite; a file whose checksum does not match is refused.
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "knit/model/model.hpp"
#include "knit/model/run_totals.hpp"
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
  /// The totals of the run that wrote the state, up to it (runner.hpp); absent for states
  /// not written by a run (a generated knit's initial.kstate, files of earlier builds).
  std::optional<RunTotals> run;
  int num_cp() const;
  int num_seg() const;
  /// Global index of the first control point of every yarn.
  std::vector<int> yarn_cp_begin() const;
};

inline constexpr unsigned STATE_FILE_VERSION = 4;

/// A relaxation's settings as the knit block writes them (by field name; the integrator by
/// its option name).
nlohmann::json to_json(const KnitRelaxSettings& settings);

/// Snapshot of a model's layout with the given state.
StateFile make_state_file(const Model& model, const State& state);
/// Writes to a temporary file beside `path` and renames it, so `path` is never half-written.
void write_state_file(const std::string& path, const StateFile& file);
/// Reads and validates; throws std::runtime_error naming the file and byte offset.
StateFile read_state_file(const std::string& path);

}  // namespace knit
