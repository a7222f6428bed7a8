// knitsim plot DIR | FILE.csv
#include <filesystem>
#include <iostream>

#include "commands.hpp"
#include "common.hpp"
#include "knit/present/plot.hpp"

namespace knitsim {

void register_plot(CLI::App& app) {
  auto input = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  CLI::App* sub = app.add_subcommand(
      "plot", "plot a run's DIR/log.csv into DIR/*.png, or any CSV (x column first) to a PNG");
  add_required_path(sub, "input", *input, "run directory holding log.csv, or a CSV file")
      ->check(existing_path());
  add_out_option(sub, *out, "output PNG for a CSV file",
                 "beside the CSV, its name ending .png (a run directory: DIR/*.png)");
  sub->callback([input, out] {
    std::vector<std::string> written;
    if (std::filesystem::is_directory(*input))
      written = knit::plot_log(*input);
    else
      written.push_back(knit::plot_csv(*input, *out));
    for (const auto& w : written) std::cout << "wrote " << w << "\n";
  });
}

const bool plot_added = add_command(50, register_plot);

}  // namespace knitsim
