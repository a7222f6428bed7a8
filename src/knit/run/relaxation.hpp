#pragma once
// Relaxation to rest (MODEL.md §6): simulate with the relaxation parameters (length
// constraints off, stiff length energy, strong global damping, rest lengths shrunk by c)
// until the yarn is at rest or a time limit passes. Two rest tests:
//  - kinetic energy: ½ vᵀMv per unit length of yarn below a threshold (the default). A
//    heavily damped sample can creep below it long before it stops changing shape.
//  - force residual: the net static force per unit mass that the constraints do not hold
//    (Simulator::force_residual) below a threshold — the yarn is at a constrained minimum
//    of the potential energy, however slowly it moves. The test for FIRE relaxations
//    (filters/fire.hpp), whose kinetic energy drops to 0 at every restart.
// Every check measures the force residual (log.csv's force_residual column) whichever
// test decides.
#include <optional>
#include <string>

#include "knit/run/runner.hpp"

namespace knit {

struct RelaxOptions {
  double max_time = 2.0;        ///< s of simulated time at most
  double ke_per_length = 1e-5;  ///< erg/cm: rest when ½ vᵀMv / L falls below
  /// cm/s²: when > 0, rest is instead the net force per unit mass falling below this
  /// (Simulator::force_residual; g = 981 cm/s²)
  double force_residual = 0;
  int check_every = 200;   ///< steps between rest checks (and written states)
  std::string out_dir;     ///< empty: write nothing
  bool overwrite = false;  ///< empty a directory that holds another run's files first
  bool progress = true;
  bool write_frames = true;
  double checkpoint_every_s = 600;  ///< RunOptions::checkpoint_every_s (without frames)
  /// The run resumes from a state of the run in out_dir and goes on there (see
  /// RunOptions::continue_in_place).
  bool continue_in_place = false;
  /// The totals of the state resumed (RunOptions::resumed_totals).
  std::optional<RunTotals> resumed_totals;
  std::string resume_command;    ///< written into the summary of an interrupted run
  int halving_calm_steps = 0;    ///< RunOptions::halving_calm_steps
  bool check_crossings = false;  ///< RunOptions::check_crossings
  /// With contact reuse (SolverSettings::contact_reuse ρ > 0): while the knit is far from
  /// rest its reuse distances widen, to ρ r · clamp(R / R₀, 1, contact_reuse_widen) with R
  /// the force residual of the last check and R₀ = contact_reuse_widen_residual
  /// (Simulator::set_reuse_scale). A knit that draws in and curls moves every control
  /// point past ρ r within a few steps, each such step paying an exact contact evaluation
  /// and a new factor of M + h² K; near rest the reuse distance is ρ r again. The checks
  /// evaluate contact exactly, so rest is the same test. 1 (the default): no widening.
  double contact_reuse_widen = 1;
  double contact_reuse_widen_residual = 20;  ///< R₀ (cm/s²)
};

/// Throws std::invalid_argument naming the option when a RelaxOptions field is out of
/// range (max_time: a duration for the solver's time step; ke_per_length finite and > 0;
/// force_residual finite and ≥ 0; check_every ≥ 1; contact_reuse_widen finite and ≥ 1, and
/// 1 unless solver.contact_reuse > 0; contact_reuse_widen_residual finite and > 0).
void validate_relax_options(const RelaxOptions& options, const SolverSettings& solver);

/// The shrink factor c of MODEL.md §6.
inline constexpr double RELAX_SHRINK = 0.935;

/// Global damping (g/s) that `knitsim relax` uses for generated knits unless told
/// otherwise: a tenth of MODEL.md §8's 1.5. With 1.5 every control point is dragged at
/// ≈ 1000/s, so the soft, sample-wide motions (edges rolling, ribs pleating, rows
/// stacking) creep: a 16×16 rib needs > 4 s of simulated time to draw in as far as it
/// does in 1 s with 0.15. Rest shapes are minima of the energies; the damping sets the
/// path to them (and a lightly damped path can swing into another minimum). With
/// none at all only the non-rigid damping filters (α = 0.3 each step) and contact damping
/// act, which leave the sheet-scale swinging of a large sample nearly undamped: a 16×16
/// garter then bows (edge curl 1.5 after 4 s) where with 0.15 it stays flat (0.16 after
/// 2 s). `--k-global 1.5` restores the paper's value. Imported yarns have no stitch
/// coordinates, hence no filters, and keep 1.5.
inline constexpr double RELAX_K_GLOBAL = 0.15;

/// Relaxes `state` in place with `sim` (whose model carries the relaxation parameters,
/// the time step and shrunk rest lengths). The summary gains `relaxed` (bool: the threshold was
/// reached), `rest_test` ("kinetic_energy" or "residual"), `ke_per_length_threshold` and
/// `ke_per_length` (erg/cm), and with the residual test `force_residual_threshold`
/// (cm/s²; the summary's `force_residual` is the last state's); with widening,
/// `contact_reuse_widen` {max, residual} (the runner's `contact_reuse_scale_mean` says how
/// wide the steps ran). `on_finish` (optional)
/// adds further fields to the summary. Throws std::invalid_argument where
/// validate_relax_options does (with the sim's solver settings).
RunReport relax(Simulator& sim, State& state, const RelaxOptions& options,
                nlohmann::json extra = nlohmann::json::object(),
                std::function<void(Simulator&, const State&, nlohmann::json&)> on_finish = {});

}  // namespace knit
