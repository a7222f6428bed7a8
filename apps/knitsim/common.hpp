#pragma once
// Small helpers shared by the subcommands.
#include <tbb/global_control.h>

#include <CLI/CLI.hpp>
#include <memory>
#include <string>
#include <vector>

#include "knit/run/runner.hpp"
#include "options.hpp"

namespace knitsim {

/// Thrown when a run ended with a failure already reported to the user (exit code 2).
struct RunFailed {};
/// Thrown when a run was interrupted by a signal and wrote its state (exit 128 + signal).
struct RunInterrupted {
  int signal;
};

/// Remembers the command line (for the summaries' provenance and resume commands).
void set_command_line(int argc, char** argv);
/// The command line as a shell would take it back (arguments quoted where needed).
std::string command_line();
/// The command line's arguments after the program name.
const std::vector<std::string>& command_args();

/// Limits TBB to `threads` workers for the lifetime of the returned object (0: no limit).
std::unique_ptr<tbb::global_control> make_thread_control(int threads);
/// Exports a finished run: usd → DIR/frames.usda (every written state as time samples),
/// obj|bcc|ply → DIR/final.<ext>. Nothing when `format` is empty.
/// A scene's `objects` go into the USD beside the yarn.
void export_run(const std::string& out_dir, const std::string& format,
                const std::vector<std::shared_ptr<const knit::SceneObject>>& objects = {});
/// One line per run: status, steps, time, where the outputs are.
void print_report(const knit::RunReport& report, const std::string& out_dir);
/// The command that resumes this command's run from OUT/final.kstate into OUT: this
/// command line with --overwrite dropped, --resume replaced, and each `replace` option
/// (name, value) set to its value.
std::string resume_command(const std::string& out_dir,
                           const std::vector<std::pair<std::string, std::string>>& replace = {});
/// Prints the report, exports, and ends the command as the run ended: returns when it was
/// ok, throws RunInterrupted or RunFailed otherwise.
void finish_run(const knit::RunReport& report, const std::string& out_dir,
                const std::string& export_format,
                const std::vector<std::shared_ptr<const knit::SceneObject>>& objects = {});
/// The objects to draw or export with `input` (a state, or a directory of states): those
/// of `scene` when given; none with `no_objects`; else those of the scene a simulation's
/// summary.json beside the input names (in the input's directory or the one above it),
/// with a note on stdout saying so.
std::vector<std::shared_ptr<const knit::SceneObject>> objects_for(const std::string& input,
                                                                  const std::string& scene,
                                                                  bool no_objects);
/// Throws RunInterrupted when the run was interrupted (after print_report).
void end_if_interrupted(const knit::RunReport& report);
/// Adds the summary's provenance fields (the command line) to `extra`.
void add_provenance(nlohmann::json& extra);

/// A summary's number for a line a user reads: 4 significant digits and the unit
/// ("2874 dyn", "0.01234 cm"); "not measured" where the summary has null (or no number).
std::string quantity(const nlohmann::json& value, const std::string& unit = "");

}  // namespace knitsim
