// knitsim version: the version and how this build was made (also `knitsim --version`).
#include <tbb/info.h>

#include <iostream>

#include "commands.hpp"
#include "common.hpp"

namespace knitsim {

void register_version(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("version", "print the version and how knitsim was built");
  cmd->callback([]() {
    std::cout << "knitsim " << knit::knitsim_version() << "\n"
#ifdef NDEBUG
              << "build: optimised"
#else
              << "build: debug"
#endif
#if defined(__SANITIZE_ADDRESS__)
              << ", address sanitizer"
#endif
              << ", " << __VERSION__ << "\n"
              << "cores available: " << tbb::info::default_concurrency() << "\n";
  });
}

const bool version_added = add_command(90, register_version);

}  // namespace knitsim
