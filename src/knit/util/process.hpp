#pragma once
// Running external tools (gnuplot, ffmpeg) without a shell, so paths need no quoting.
#include <string>
#include <vector>

namespace knit {

/// The executable `name` found on PATH, or "" when there is none.
std::string find_executable(const std::string& name);

/// Runs argv[0] (a path) with the arguments, stdout discarded, and waits. Returns the exit
/// status (128 + signal when killed); `messages` receives what it wrote to stderr.
/// Throws std::runtime_error when it cannot be started.
int run_process(const std::vector<std::string>& argv, std::string& messages);

}  // namespace knit
