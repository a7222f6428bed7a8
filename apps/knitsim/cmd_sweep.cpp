// knitsim sweep SPEC --out DIR [--workers N] [--scheduler ADDRESS] [--threads N] [--quiet]:
// a table of jobs on a Dask cluster. The sweep layer is Python over the module's recipes
// (python/knitsim_sweep.py, which declares the options and says what they do); this command
// runs it with Debian's python3, finding it beside this program's build (build/python) or
// where scripts/setup.sh installed it. Every argument is passed through.
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "commands.hpp"

namespace knitsim {

namespace {

// the folder of the build's Python module and sweep layer, when this program is a build's
std::string build_python_dir() {
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) return "";
  const std::filesystem::path dir = exe.parent_path() / "python";
  return std::filesystem::exists(dir / "knitsim_sweep.py", ec) ? dir.string() : "";
}

[[noreturn]] void run_sweep(const std::vector<std::string>& args) {
  if (const std::string dir = build_python_dir(); !dir.empty()) {
    const char* old = std::getenv("PYTHONPATH");
    const std::string path = dir + (old && *old ? ":" + std::string(old) : "");
    ::setenv("PYTHONPATH", path.c_str(), 1);
  }
  const char* python = ::access("/usr/bin/python3", X_OK) == 0 ? "/usr/bin/python3" : "python3";
  std::vector<std::string> argv = {python, "-m", "knitsim_sweep"};
  argv.insert(argv.end(), args.begin(), args.end());
  std::vector<char*> cargv;
  for (std::string& a : argv) cargv.push_back(a.data());
  cargv.push_back(nullptr);
  std::cout.flush();
  ::execvp(python, cargv.data());
  std::cerr << "knitsim: error: sweep: cannot run " << python << ": " << std::strerror(errno)
            << " (the sweep layer needs Debian's python3 with python3-distributed; "
               "scripts/setup.sh installs it)\n";
  std::exit(1);
}

}  // namespace

void register_sweep(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand(
      "sweep",
      "run a sweep spec's jobs (relax, stretch, simulate over a grid) on a Dask cluster; "
      "`knitsim sweep --help` for its options (docs/sweeps.md)");
  // its options are the sweep layer's (python/knitsim_sweep.py): all passed through
  cmd->prefix_command();
  cmd->set_help_flag();
  cmd->allow_extras();
  cmd->callback([cmd]() { run_sweep(cmd->remaining()); });
}

const bool sweep_added = add_command(75, register_sweep);

}  // namespace knitsim
