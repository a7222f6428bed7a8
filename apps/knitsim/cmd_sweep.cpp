// knitsim sweep SPEC --out DIR [--workers N | --scheduler ADDRESS] [--threads N] [--quiet]:
// a table of jobs on a Dask cluster. The options are declared here; the sweep layer is
// Python over the module's recipes (python/knitsim_sweep.py, docs/sweeps.md), which this
// command runs with Debian's python3 (knitsim_sweep.run_command, given the options as
// JSON), finding it beside this program's build (build/python) or where scripts/setup.sh
// installed it.
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "commands.hpp"
#include "common.hpp"

namespace knitsim {

namespace {

struct SweepOptions {
  std::string spec, out, scheduler;
  int workers = 0, threads = 1;
  bool quiet = false;
};

// the folder of the build's Python module and sweep layer, when this program is a build's
std::string build_python_dir() {
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) return "";
  const std::filesystem::path dir = exe.parent_path() / "python";
  return std::filesystem::exists(dir / "knitsim_sweep.py", ec) ? dir.string() : "";
}

[[noreturn]] void run_sweep(const SweepOptions& o) {
  if (const std::string dir = build_python_dir(); !dir.empty()) {
    const char* old = std::getenv("PYTHONPATH");
    const std::string path = dir + (old && *old ? ":" + std::string(old) : "");
    ::setenv("PYTHONPATH", path.c_str(), 1);
  }
  const nlohmann::json options = {{"spec", o.spec},           {"out", o.out},
                                  {"scheduler", o.scheduler}, {"workers", o.workers},
                                  {"threads", o.threads},     {"progress", !o.quiet}};
  const char* python = ::access("/usr/bin/python3", X_OK) == 0 ? "/usr/bin/python3" : "python3";
  std::vector<std::string> argv = {
      python, "-c", "import sys, knitsim_sweep; sys.exit(knitsim_sweep.run_command(sys.argv[1]))",
      options.dump()};
  std::vector<char*> cargv;
  for (std::string& a : argv) cargv.push_back(a.data());
  cargv.push_back(nullptr);
  std::cout.flush();
  ::execvp(python, cargv.data());
  std::cerr << "knitsim: error: sweep: cannot run " << python << ": " << std::strerror(errno)
            << " (the sweep layer needs Debian's python3 with python3-distributed; "
               "scripts/setup.sh installs them)\n";
  std::exit(EXIT_ERROR);
}

}  // namespace

void register_sweep(CLI::App& app) {
  auto o = std::make_shared<SweepOptions>();
  CLI::App* cmd = app.add_subcommand(
      "sweep",
      "run a sweep spec's jobs (relax, stretch, simulate over a grid or a list) on a Dask "
      "cluster: each its own run directory, their table and plots (docs/sweeps.md)");
  add_required_path(cmd, "spec", o->spec, "the sweep spec (JSON: kind, args, grid, jobs)")
      ->check(existing_file());
  add_out_option(cmd, o->out,
                 "the sweep's directory: new, empty, or an earlier sweep's, which it goes on "
                 "with (only its unfinished jobs run)");
  add_integer(cmd, "--workers", o->workers,
              "worker processes of the local cluster (one job each at a time)", 0, 4096, "count",
              "0 (one per core)");
  add_text(cmd, "--scheduler", o->scheduler,
           "a running Dask scheduler's address instead of a local cluster (its workers must "
           "import the same knitsim and read the same paths)",
           "address (tcp://HOST:PORT)", "none (a local cluster)");
  add_integer(cmd, "--threads,-j", o->threads, "threads of each job", 0, 4096, "count",
              "1 (0: all cores)");
  add_quiet_flag(cmd, o->quiet);
  cmd->callback([o] { run_sweep(*o); });
}

const bool sweep_added = add_command(75, register_sweep);

}  // namespace knitsim
