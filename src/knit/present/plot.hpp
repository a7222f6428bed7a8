#pragma once
// Plots of simulation logs and measured curves, drawn by gnuplot (run as a subprocess,
// pngcairo terminal). Outputs are written to a temporary name and renamed, so a PNG is
// never half-written.
#include <string>
#include <vector>

#include "knit/io/csv.hpp"

namespace knit {

/// Throws std::invalid_argument (naming `option`, when given, and the path) unless `path`
/// ends in .png: plots are PNG images, and a PNG under another name would mislead.
void check_plot_path(const std::string& path, const std::string& option = "");

/// "displacement_cm" → "displacement (cm)", "kinetic_energy" → "kinetic energy": a
/// trailing known unit token (cm, s, g, dyn, erg, …) becomes a parenthesised unit.
std::string axis_label(const std::string& column);

/// The gnuplot executable found on PATH, or "" when there is none.
std::string find_gnuplot();

/// The columns a simulation log (DIR/log.csv) must have.
const std::vector<std::string>& log_columns();

/// Plots `dir`/log.csv into `dir`: energy.png (kinetic, potential, total; erg),
/// constraints.png (max violation), contact.png (pairs and min distance) and timing.png
/// (wall time per step), and forces.png (|F| of every pin, glue and clamp, dyn) when the
/// log has their columns. Returns the paths written. Throws when gnuplot is missing or
/// the log is malformed.
std::vector<std::string> plot_log(const std::string& dir);

/// Plots every column of a CSV against its first (e.g. displacement_cm,force_dyn) into
/// `out_png` (default: the CSV path with extension .png). Returns the path written.
std::string plot_csv(const std::string& csv, const std::string& out_png = "");

/// One labelled curve.
struct PlotSeries {
  std::string label;
  std::vector<double> x, y;
};

/// Draws several curves (each with its own samples) in one plot with a legend into
/// `out_png`. Returns the path written. Throws when gnuplot is missing or nothing is given.
std::string plot_series(const std::vector<PlotSeries>& series, const std::string& xlabel,
                        const std::string& ylabel, const std::string& title,
                        const std::string& out_png);

}  // namespace knit
