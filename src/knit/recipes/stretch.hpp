#pragma once
// Recipe: "stretch a sample" — a tensile test of a relaxed knit. Its first and last
// `clamp_stitches` columns (course), rows (wale) or opposite corners (bias, the stitches
// within clamp_stitches rows and columns of the corner) are held by clamps; the first
// clamp holds still, the second moves away along the line between the clamps' centres at
// a constant speed until the nominal strain (separation / initial separation − 1) reaches
// `to_strain`, then back and forth for `cycles` more half-cycles. The simulation
// parameters of MODEL.md §8 apply, without gravity (a sample on a tensile tester).
//
// Recorded at every written state (StretchSample): nominal strain, the force each clamp
// exerts along the pull axis (from the clamps' constraint records, positive in tension),
// the sample's width across the pull at its middle, energies and closest approach.
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "knit/io/state_file.hpp"
#include "knit/model/model.hpp"
#include "knit/model/params.hpp"
#include "knit/run/runner.hpp"

namespace knit {

enum class StretchDirection { COURSE, WALE, BIAS };

struct StretchSample;

/// "course", "wale" or "bias"; throws std::invalid_argument naming the value otherwise.
StretchDirection parse_stretch_direction(const std::string& name);
const char* stretch_direction_name(StretchDirection direction);

/// MODEL.md §8's simulation column without gravity, 10 contact points per segment.
Params stretch_params();

struct StretchOptions {
  StretchDirection direction = StretchDirection::COURSE;
  double to_strain = 1.0;  ///< nominal strain at the end of the pull (1: doubled length)
  int cycles = 0;          ///< further half-cycles after the pull (back, out, …)
  double speed = 5.0;      ///< the moving clamp's speed (cm/s)
  int clamp_stitches = 2;  ///< columns, rows or corner size held by each clamp
  /// a sample (and a written state) every this much strain (a pull to less is sampled at
  /// its start and end: sample_strain)
  double output_strain = 0.01;
  /// > 0: the held protocol. The clamp moves (at `speed`) in steps of this much
  /// strain and stands still for `hold_time` s after each (and once at strain 0 before the
  /// first), while FIRE relaxes the yarn to rest (filters/hold_relax.hpp); the curve is
  /// sampled at the end of each hold, with the clamps' static reactions
  /// (StepData::static_constraints) as the forces and the force residual as how near to
  /// rest each sample is. Global damping is off (k_global = 0): it is zero at rest. 0: a
  /// continuous pull at `speed`, sampled every `output_strain`.
  double hold_strain = 0;
  double hold_time = 0.3;  ///< s of each hold (with hold_strain)
  /// > 0: a load limit, as on a tensile tester: the pull ends (status ok) at the first
  /// sample (every output_strain, or a hold's end) where either clamp's force along the pull
  /// exceeds this (dyn). The summary's stretch.stopped says at what strain and force. 0: none. A
  /// knit pulled until its yarns jam (along the bias from corner clamps) otherwise goes on until
  /// the contact penalty gives way and a step fails.
  double max_force = 0;
  /// With hold_strain: hold with the simulation's own damping (the non-rigid damping
  /// filter and global damping) instead of FIRE — a stress-relaxation test: the force
  /// decays through each hold as the damped knit creeps, sampled at its end.
  bool hold_damped = false;
  Params params = stretch_params();
  std::string out_dir;  ///< empty: write nothing
  bool overwrite = false;
  /// Go on with the stopped run in out_dir (interrupted, or killed: stretch.csv grows with
  /// every sample) from this state of it: its final.kstate, one of its frames, or out_dir
  /// itself for the latest state it has a sample of (stretch_resume_state). The pull must be
  /// the run's own (knit, direction, strain, speed, cycles: checked against the summary
  /// when there is one and against the strain of the last sample); the curve so far is read
  /// back from stretch.csv (rows after the state dropped) and the run goes on in place to
  /// the same end. Continuous pulls only (a hold's FIRE state is not in the frames). With
  /// yarn friction, the friction filter's warm start begins again at the resumed state.
  std::string resume;
  std::string resume_command;  ///< written into the summary of an interrupted run
  bool progress = true;
  bool write_frames = true;
  bool check_crossings = false;  ///< RunOptions::check_crossings (the pull's run)
  /// with out_dir and frames: renders of the sample at strains 0, 0.25, 0.5 and 1 (those up
  /// to to_strain, and to_strain itself) side by side in stretch_renders.png (each also as
  /// `renders/strain_<e>.png`), and a movie of every frame in movie/animation.mp4
  bool render = true;
  int render_width = 640, render_height = 480;
  nlohmann::json extra = nlohmann::json::object();  ///< merged into the summary
  /// Draws the figures of a pull into out_dir after its stretch.csv is written: the force
  /// and width plots and, when `render`, the renders and movie (arguments: these options,
  /// the curve, the title, whether the pull has ended); returns the summary's "renders"
  /// entry, or null. The study draws nothing itself (presentation sits above it): the front
  /// ends set this to knit::write_stretch_figures (present/stretch_figures.hpp); empty, a
  /// run writes no pictures.
  std::function<nlohmann::json(const StretchOptions&, const std::vector<StretchSample>&,
                               const std::string&, bool)>
      figures;
};

/// One sample of the curve.
struct StretchSample {
  double time = 0;                  ///< s
  double strain = 0;                ///< nominal strain
  double force_fixed = 0;           ///< force of the fixed clamp along −axis (dyn; tension > 0)
  double force_moving = 0;          ///< force of the moving clamp along +axis (dyn)
  double width = 0;                 ///< extent across the pull in the middle band (cm)
  double potential_energy = 0;      ///< erg
  double kinetic_energy = 0;        ///< erg
  double min_contact_distance = 0;  ///< d = distance / 2r over contact pairs (−1: none)
  /// the edges' roll out of the fabric's plane, in stitch widths (FabricShape::edge_curl;
  /// clamped edges are held flat, so a course pull shows the top and bottom edges' curl)
  double edge_curl = 0;
  /// The force residual at the sample (cm/s²; Simulator::force_residual), measured by the
  /// held protocol; NaN otherwise.
  double force_residual = std::numeric_limits<double>::quiet_NaN();
  /// A sample at the end of a hold (the held protocol's curve); false for the
  /// unrelaxed start and for every sample of a continuous pull.
  bool equilibrium = false;
};

struct StretchResult {
  RunReport report;  ///< the run; its summary holds the stretch measures below
  std::vector<StretchSample> curve;
  double initial_separation = 0;  ///< distance between the clamps' centres at t = 0 (cm)
  double speed = 0;  ///< the moving clamp's speed as run: each pull a whole number of steps
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();  ///< pull direction (unit)
};

/// Throws std::invalid_argument naming the option when a StretchOptions field is out of
/// range.
void validate_stretch_options(const StretchOptions& options);

/// The strain between two samples of a continuous pull: output_strain, or the whole pull
/// when it is shorter (a pull to 0.005 is sampled at 0 and 0.005).
double sample_strain(const StretchOptions& options);

/// What a user should know before trusting the curve of a pull with these options (empty
/// when nothing): combinations that run but are known to give another curve than the
/// explicit step. Written to the summary as "caveats"; the command prints them.
std::vector<std::string> stretch_caveats(const StretchOptions& options);

/// What a stretch test of a relaxed knit holds and measures, before it runs: the knit,
/// its two clamps (the control points they hold and their centres), the pull axis (from
/// the fixed clamp's centre to the moving one's), the initial separation of the centres,
/// the sample's normal (its direction of least spread) and the axis across the pull in the
/// fabric.
struct StretchGeometry {
  StateFile file;
  Model model;  ///< the knit with the two clamps, as the yarn test builds it
  Clamp fixed, moving;
  Eigen::VectorXd q0;  ///< the knit's control points as placed (cm)
  double radius = 0;   ///< yarn radius (cm)
  double separation = 0;
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX(), across = Eigen::Vector3d::UnitY(),
                  normal = Eigen::Vector3d::UnitZ(), centroid = Eigen::Vector3d::Zero();
  /// The sample's width across the pull (cm): the extent along `across` of the control
  /// points within half a cm of the middle between the clamps, the moving one `moved` cm
  /// along the axis, plus a yarn diameter.
  double width(const Eigen::VectorXd& q, double moved) const;
};

/// Validates the sample against the options (stitch coordinates present, enough rows or
/// columns for two clamps) and measures its geometry. Throws std::invalid_argument.
StretchGeometry stretch_geometry(const std::string& kstate_path, const StretchOptions& options);

/// "PATTERN, DIRECTION" for titles.
std::string stretch_label(const StateFile& file, StretchDirection direction);

/// After a run that wrote its summary (and frames) into options.out_dir: stretch.csv, then
/// options.figures (plots titled with `label`; when `ended` and options.render, renders
/// and movie, listed in the summary's "renders"). A pull has ended when it reached its
/// strain or stopped for good (unstable): then it is rendered up to the last strain it
/// reached; an interrupted one goes on with --resume and is rendered when it ends.
void write_stretch_outputs(const StretchOptions& options, const std::vector<StretchSample>& curve,
                           const std::string& label, bool ended);

/// Stretches the relaxed knit in `kstate_path` (written by `knitsim relax`). With out_dir,
/// writes the run (frames, log.csv, final.kstate) and stretch.csv, a summary.json with
/// the stretch measures (see stretch_measures) and stretch_force.png / stretch_width.png,
/// and (options.render) the renders and movie.
/// Throws std::invalid_argument naming the option on bad input, before anything is written.
StretchResult stretch_knit(const std::string& kstate_path, const StretchOptions& options);

/// Measures of a curve, for the summary: initial_separation_cm, stiffness_small_strain
/// (least-squares slope of the moving clamp's force against strain over the first tenth
/// of the pull, the rest sample at strain 0 left out, dyn per unit strain), stiffness_end (over the
/// last tenth of --to of the pull it made: up to `to_strain`, or up to where it stopped),
/// stiffening_strain (the first strain where the slope over a window of a tenth of the pull reaches
/// three times the small-strain slope; null if never), work_erg (∫ F dx of the moving clamp over
/// the whole run), max_force_dyn, width_change (width at the end of the pull over the initial
/// width, − 1). With hold_strain > 0 (the held protocol) only the samples at the holds' ends count,
/// the rest sample at strain 0 among them (it has no drag), and each window spans at least two
/// holds.
nlohmann::json stretch_measures(const std::vector<StretchSample>& curve, double to_strain,
                                double initial_separation, double hold_strain = 0);

/// The latest state of the stopped stretch run in `out_dir` that its stretch.csv has a
/// sample of: final.kstate when the run was interrupted (its summary says so), else the
/// last frame whose time has a row. Throws std::invalid_argument naming what is missing.
std::string stretch_resume_state(const std::string& out_dir);

/// Reads a stretch.csv written by write_stretch_csv (force_residual −1 reads as NaN).
/// Throws std::runtime_error naming the file on malformed input.
std::vector<StretchSample> read_stretch_csv(const std::string& path);

/// Writes the samples as CSV: time_s, strain, force_fixed_dyn, force_moving_dyn, width_cm,
/// potential_energy_erg, kinetic_energy_erg, min_contact_distance, edge_curl,
/// force_residual (cm/s²; −1 when not measured), equilibrium (1 at the end of a hold).
void write_stretch_csv(const std::vector<StretchSample>& curve, const std::string& path);

}  // namespace knit
