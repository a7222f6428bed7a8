#pragma once
// How the commands declare their options, so that every `--help` says of each value the
// same three things the same way (docs/cli.md, "Reading --help"): the last line of an
// option's description is
//     unit: UNIT; default: DEFAULT; range: RANGE
// (a range for numbers only). The options several commands take are declared here once
// (name, unit, range, one line of doc); each command gives its default, the value its
// library recipe starts from, so that no default is typed twice.
#include <CLI/CLI.hpp>
#include <memory>
#include <string>
#include <vector>

#include "knit/model/params.hpp"

namespace knitsim {

/// The range of a numeric option: [lo, hi], or (lo, hi] with `open_low`.
struct Range {
  double lo, hi;
  bool open_low = false;
};
/// [lo, hi]
inline Range closed(double lo, double hi) {
  return {lo, hi, false};
}
/// (0, hi]: a positive number at most hi.
inline Range positive(double hi) {
  return {0, hi, true};
}
/// A scene parameter's working range (knit::param_table(), by its name).
Range param(const std::string& name);

/// "[0, 1]", "(0, 100000]".
std::string range_text(const Range& r);
/// A number for help texts: knit::short_number, and "8.47458e-05 (1/11800)" for the
/// reciprocal of a whole number other than a power of ten (a time step).
std::string number_text(double x);
/// The last line of an option's description: "unit: …; default: …[; range: …]".
std::string value_line(const std::string& unit, const std::string& default_text,
                       const std::string& range = "");

/// CLI11 checks without a description of their own (the value line says the range): a
/// finite number in `r`, an integer in [lo, hi]. Their messages name the value and range.
CLI::Validator number_in(const Range& r);
CLI::Validator integer_in(long long lo, long long hi);
/// CLI::ExistingFile and CLI::ExistingPath, their descriptions left to the value line.
CLI::Validator existing_file();
CLI::Validator existing_path();

/// A FLOAT option in `range`, `unit`; its default is `value` as it stands (the recipe's
/// own) unless `default_text` says otherwise.
CLI::Option* add_number(CLI::App* cmd, const std::string& names, double& value,
                        const std::string& doc, const std::string& unit, const Range& range,
                        const std::string& default_text = "");
/// An INT option in [lo, hi] (unit "count" unless said), default `value` unless said.
CLI::Option* add_integer(CLI::App* cmd, const std::string& names, int& value,
                         const std::string& doc, long long lo, long long hi,
                         const std::string& unit = "count", const std::string& default_text = "");
/// A PATH option (or positional); `default_text` says what happens without it.
CLI::Option* add_path(CLI::App* cmd, const std::string& names, std::string& value,
                      const std::string& doc, const std::string& default_text,
                      const std::string& unit = "path");
/// A required PATH option (or positional).
CLI::Option* add_required_path(CLI::App* cmd, const std::string& names, std::string& value,
                               const std::string& doc, const std::string& unit = "path");
/// A TEXT option (or positional): free text, a list, a size.
CLI::Option* add_text(CLI::App* cmd, const std::string& names, std::string& value,
                      const std::string& doc, const std::string& unit,
                      const std::string& default_text, const std::string& range = "");
/// A NAME option: one of `choices`, default `value` unless said.
CLI::Option* add_choice(CLI::App* cmd, const std::string& names, std::string& value,
                        const std::string& doc, const std::vector<std::string>& choices,
                        const std::string& default_text = "");

/// The exit codes (docs/cli.md, "Exit codes"); an interrupted run exits 128 + the signal.
inline constexpr int EXIT_OK = 0, EXIT_ERROR = 1, EXIT_RUN_FAILED = 2;
/// The epilogue of every --help: the exit codes, and where the options are explained.
std::string help_footer();
/// The formatter of every --help: descriptions wrapped to the terminal's 100 columns.
std::shared_ptr<CLI::Formatter> help_formatter();

/// The group the solver options go in, in every command that takes them.
extern const char* const SOLVER_GROUP;

// ------------------------------------------------------------------ shared options
// Each is declared once here; `default_text` empty: the value passed in as it stands.

/// --out,-o DIR or FILE (required unless `default_text` says what happens without it).
CLI::Option* add_out_option(CLI::App* cmd, std::string& out, const std::string& doc,
                            const std::string& default_text = "");
/// --overwrite: replace the files of an earlier run in the output directory.
void add_overwrite_flag(CLI::App* cmd, bool& overwrite, const std::string& doc = "");
/// --quiet,-q: no progress line.
void add_quiet_flag(CLI::App* cmd, bool& quiet);
/// --check-crossings: check every step for yarns passing through each other
/// (knit::RunOptions::check_crossings).
void add_check_crossings_flag(CLI::App* cmd, bool& check);
/// --threads,-j N (0 = all cores).
void add_threads_option(CLI::App* cmd, int& threads);
/// --export usd|obj|bcc|ply|… (knit::export_formats()).
void add_export_option(CLI::App* cmd, std::string& format);
/// --rows and --cols of a generated knit; `default_note` follows each default.
void add_size_options(CLI::App* cmd, int& rows, int& cols, const std::string& rows_doc,
                      const std::string& cols_doc, const std::string& default_note = "");

// the solver group
/// --time-step (s).
void add_time_step_option(CLI::App* cmd, double& time_step, const std::string& default_text = "");
/// --integrator explicit|imex|imex-contact (knit::Integrator).
void add_integrator_option(CLI::App* cmd, std::string& integrator,
                           const std::string& default_text = "");
/// --implicit-bending (knit::SolverSettings::implicit_bending), with --no-implicit-bending
/// where `negatable` (a resumed relaxation's own setting turned off).
void add_implicit_bending_option(CLI::App* cmd, bool& implicit_bending, bool negatable = false);
/// --contact-solve-tolerance: imex-contact's conjugate-gradient tolerance.
void add_contact_solve_tolerance_option(CLI::App* cmd, double& tolerance,
                                        const std::string& default_text = "");
/// --contact-reuse (SolverSettings::contact_reuse, yarn radii).
void add_contact_reuse_option(CLI::App* cmd, double& reuse, const std::string& default_text = "");
/// --refuse-crossings (SolverSettings::refuse_crossings), with --no-refuse-crossings where
/// `negatable` (a resumed relaxation's own setting turned off).
void add_refuse_crossings_option(CLI::App* cmd, bool& refuse, bool negatable = false);
/// --max-step-halvings (SolverSettings::max_step_halvings).
void add_max_step_halvings_option(CLI::App* cmd, int& halvings,
                                  const std::string& default_text = "");
/// --end-mass-floor (Discretisation::end_mass_floor, a fraction of an interior mass).
void add_end_mass_floor_option(CLI::App* cmd, double& floor);
/// --contact-points (Discretisation::contact_points).
void add_contact_points_option(CLI::App* cmd, int& points);
/// --alpha-small and --alpha-large (Material::alpha_small, alpha_large): the non-rigid
/// damping filter's strengths, per 1/11800 s.
void add_damping_options(CLI::App* cmd, knit::Material& material);

}  // namespace knitsim
