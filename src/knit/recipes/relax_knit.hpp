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
#include "knit/solver/relaxation.hpp"

namespace knit {

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

/// The set-up of relax_knit without the run: the generated knit, the simulator (model
/// with shrunk rest lengths and closing glues, model.knit set, non-rigid damping filter)
/// and the state to start from. For tests and callers that step by hand.
struct KnitRelaxation {
  GeneratedKnit knit;
  std::unique_ptr<Simulator> sim;
  State state;
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
