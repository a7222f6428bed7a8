#pragma once
// Recipe: "relax a knit" (MODEL.md §6). Generate a pattern's interlocked yarn, shrink its
// rest lengths, and simulate it with the relaxation parameters until it comes to rest.
// `knitsim relax`, bench_relax, the tests and the Python module all call this; the
// defaults below are the ones `knitsim relax` documents.
//
//   RelaxKnitOptions o;            // 12 × 12 … see below
//   o.knit.rows = 42; o.knit.cols = 32;
//   const RelaxResult r = relax_knit("rib2x2", o);   // nothing written: o.run.out_dir empty
//   r.state.q …                                      // the relaxed control points
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "knit/io/import.hpp"
#include "knit/model/model.hpp"
#include "knit/model/state.hpp"
#include "knit/pattern/generator.hpp"
#include "knit/run/relaxation.hpp"

namespace knit {

class FireFilter;

/// The force-residual rest threshold of FIRE relaxations unless told otherwise (cm/s²):
/// the net force on the yarn a thousandth of its weight.
inline constexpr double RELAX_FIRE_RESIDUAL = 1.0;

/// Seconds over which a generated knit's glued yarn ends are drawn onto the points they
/// are glued to (they are laid a yarn diameter away).
inline constexpr double RELAX_GLUE_CLOSE_TIME = 0.05;

/// The parameters `relax_knit` uses unless told otherwise: MODEL.md §8's relaxation column,
/// gravity off (the sample relaxes in free space), global damping RELAX_K_GLOBAL (see
/// relaxation.hpp for why a tenth of the table's), 10 contact points per segment,
/// h = 1/11800 s.
Params relax_knit_params();

struct RelaxKnitOptions {
  KnitOptions knit = [] {
    KnitOptions k;
    k.rows = 12;
    k.cols = 12;
    return k;
  }();                                             ///< size and layout (default 12 × 12, flat)
  double shrink = RELAX_SHRINK;                    ///< rest-length factor c
  double glue_close_time = RELAX_GLUE_CLOSE_TIME;  ///< s
  Params params = relax_knit_params();
  /// Relax by minimisation (FIRE, filters/fire.hpp) instead of damped dynamics: the FIRE
  /// filter replaces the non-rigid damping filter, global damping is off whatever
  /// params say, and rest is the force-residual test (run.force_residual, or
  /// RELAX_FIRE_RESIDUAL when it is 0).
  bool fire = false;
  RelaxOptions run;  ///< time limit, rest threshold, output directory (empty: write nothing)
  /// Go on from this state (same knit: see read_resumed_knit_state); its time carries on,
  /// so glues go on closing where they were.
  const State* resume = nullptr;
  nlohmann::json extra = nlohmann::json::object();  ///< merged into the summary
};

struct RelaxResult {
  Model model;  ///< with model.knit set
  State state;  ///< the last state (the last good one when the run failed)
  RunReport report;
};

/// The working range of the knit options for relaxation at the default time step
/// (1/11800 s), measured on 4×4 stockinette, garter and 2×2 rib over 0.03–0.05 s: outside
/// it a relaxation goes unstable within a few steps (README, "Guarantees").
///   segments per stitch: 6, 7, 8 relax; 4, 5 and 9–16 blow up within 0–7 steps
///   shrink: 0.9–1 relax; 0.85 blows up after 8 steps, 0.8 and below at once
inline constexpr int MIN_SEGMENTS_PER_STITCH = 6, MAX_SEGMENTS_PER_STITCH = 8;
inline constexpr double MIN_SHRINK = 0.9, MAX_SHRINK = 1.0;
/// Stitch size (yarn length per stitch) in yarn radii: 4–20 cm relax at r = 0.125 cm
/// (3.5 cm blows up after 15 steps, 2–3 cm at once); from 20 cm the loops barely touch and
/// at 30 cm no yarn touches another: the fabric no longer holds together.
inline constexpr double MIN_STITCH_SIZE_RADII = 32, MAX_STITCH_SIZE_RADII = 96;
/// Fewest stitches around a tube knit in the round (3 blows up after 10 steps; 4–6 relax).
inline constexpr int MIN_ROUND_COLS = 4;
/// Largest knit accepted (segments), and the memory a relaxation takes per segment at 10
/// contact points (bytes), checked against the machine's available memory before
/// anything is generated. Measured: 12×12 → 42×32 stockinette (1,184 → 10,844 segments)
/// raises the peak resident size from 12.7 to 48.2 MB, 3.7 kB per segment; twice that
/// leaves room for the contact set growing as the knit draws in.
inline constexpr long long MAX_KNIT_SEGMENTS = 20'000'000;
inline constexpr double RELAX_BYTES_PER_SEGMENT = 8e3;

/// Throws std::invalid_argument naming the option when the shrink factor is outside
/// [MIN_SHRINK, MAX_SHRINK] (or not finite).
void check_shrink(double shrink);
/// Throws std::invalid_argument naming the option and its working range when a knit
/// cannot be relaxed as asked: at least 2 rows and 2 columns (MIN_ROUND_COLS in the
/// round), segments per stitch, stitch size and shrink within their ranges, and a size
/// whose estimated memory fits in the machine's available memory.
void check_knit_relaxation(const KnitOptions& knit, double shrink, const Params& params);

/// Throws std::invalid_argument when `pattern` is a knitout program (knitout.hpp) and the
/// knit options ask for another size or flat/round than it knits: a program is knitted as
/// written, never repeated or cut.
void check_knitout_size(const std::string& pattern, const KnitOptions& knit);

/// The set-up of relax_knit without the run: the generated knit, the simulator (model
/// with shrunk rest lengths and closing glues, model.knit set, non-rigid damping filter)
/// and the state to start from. For tests and callers that step by hand.
struct KnitRelaxation {
  GeneratedKnit knit;
  std::unique_ptr<Simulator> sim;
  State state;
  const FireFilter* fire = nullptr;  ///< the sim's FIRE filter (with RelaxKnitOptions::fire)
};
KnitRelaxation setup_knit_relaxation(const std::string& pattern, const RelaxKnitOptions& options);

/// Relaxes `pattern` (a built-in name or a chart file). With run.out_dir set, writes the
/// run's outputs there (initial.kstate, frames/, log.csv, summary.json with the generated
/// and relaxed fabric shape, final.kstate and relaxed.kstate). Throws
/// std::invalid_argument naming the option on bad input, before anything is written.
RelaxResult relax_knit(const std::string& pattern, const RelaxKnitOptions& options);

/// The state of an earlier relaxation of the same knit (`pattern` at options.knit), read
/// from `path`: same control-point count, the same stitch of every segment, and (when
/// the file says) the same pattern, size and flat/round; else an error naming the file
/// and what differs.
State read_resumed_knit_state(const std::string& path, const std::string& pattern,
                              const KnitOptions& options);

/// The options of `o` that say how a knit is relaxed (method, solver settings, damping
/// asked for, rest test, contact-reuse widening), as every state of the relaxation records
/// them (KnitInfo::relaxation); apply_relax_settings sets them back into `o` (the knit,
/// the run's time limit and outputs are left as they are).
KnitRelaxSettings relax_settings(const RelaxKnitOptions& o);
void apply_relax_settings(const KnitRelaxSettings& s, RelaxKnitOptions& o);

/// The parameters `relax_yarns` uses unless told otherwise: the relaxation column with
/// gravity off and the table's k_global = 1.5 (imported yarns have no stitch coordinates,
/// hence no non-rigid damping), h = 1/25000 s (imported swatches start tightly packed).
Params relax_yarns_params();

struct RelaxYarnsOptions {
  ImportOptions import;  ///< scale and sampling of the file's polylines
  double shrink = RELAX_SHRINK;
  Params params = relax_yarns_params();  ///< material.radius is set from import.radius
  RelaxOptions run;
  nlohmann::json extra = nlohmann::json::object();
};

/// Relaxes the yarns of a .yarns, .bcc or .obj file (no stitch coordinates: no non-rigid
/// damping and no shape measures). Writes initial.kstate, final.kstate, relaxed.kstate, …
/// into run.out_dir when set.
RelaxResult relax_yarns(const std::string& path, const RelaxYarnsOptions& options);

}  // namespace knit
