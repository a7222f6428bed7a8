#pragma once
// Each subcommand of the knitsim program registers itself on the CLI11 app.
#include <CLI/CLI.hpp>

namespace knitsim {

void register_simulate(CLI::App& app);
void register_relax(CLI::App& app);
void register_export(CLI::App& app);
void register_render(CLI::App& app);
void register_plot(CLI::App& app);
void register_stretch(CLI::App& app);
void register_version(CLI::App& app);
void register_mesh(CLI::App& app);
void register_view(CLI::App& app);
void register_graph(CLI::App& app);

}  // namespace knitsim
