#pragma once
// Small helpers shared by the subcommands.
#include <tbb/global_control.h>

#include <CLI/CLI.hpp>
#include <memory>
#include <string>

#include "knit/solver/runner.hpp"

namespace knitsim {

/// Thrown when a run ended with a failure already reported to the user (exit code 2).
struct RunFailed {};

/// Adds --threads N (0 = all cores).
void add_threads_option(CLI::App* cmd, int& threads);
/// Limits TBB to `threads` workers for the lifetime of the returned object (0: no limit).
std::unique_ptr<tbb::global_control> make_thread_control(int threads);
/// Adds --export usd|obj|bcc|ply.
void add_export_option(CLI::App* cmd, std::string& format);
/// Exports a finished run: usd → DIR/frames.usda (every written state as time samples),
/// obj|bcc|ply → DIR/final.<ext>. Nothing when `format` is empty.
void export_run(const std::string& out_dir, const std::string& format);
/// One line per run: status, steps, time, where the outputs are.
void print_report(const knit::RunReport& report, const std::string& out_dir);

}  // namespace knitsim
