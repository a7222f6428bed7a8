// knitsim plot DIR | FILE.csv
#include <filesystem>
#include <iostream>

#include "commands.hpp"
#include "knit/io/plot.hpp"

namespace knitsim {

void register_plot(CLI::App& app) {
  auto input = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  CLI::App* sub = app.add_subcommand(
      "plot", "plot a run's DIR/log.csv into DIR/*.png, or any CSV (x column first) to a PNG");
  sub->add_option("input", *input, "run directory holding log.csv, or a CSV file")
      ->required()
      ->check(CLI::ExistingPath);
  sub->add_option("--out,-o", *out, "output PNG for a CSV file (default: beside it)");
  sub->callback([input, out] {
    std::vector<std::string> written;
    if (std::filesystem::is_directory(*input))
      written = knit::plot_log(*input);
    else
      written.push_back(knit::plot_csv(*input, *out));
    for (const auto& w : written) std::cout << "wrote " << w << "\n";
  });
}

}  // namespace knitsim
