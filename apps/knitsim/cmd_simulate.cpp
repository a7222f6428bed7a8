#include "commands.hpp"
namespace knitsim {
void register_simulate(CLI::App& app) { app.add_subcommand("simulate", "run a scene file"); }
}  // namespace knitsim
