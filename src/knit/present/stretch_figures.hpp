#pragma once
// The figures of stretch tests (recipes/stretch.hpp): the force and width plots of a pull,
// the renders of its sample at chosen strains and its movie, and the curves of several
// runs in one plot. The front ends hand write_stretch_figures to the study
// (StretchOptions::figures), which draws nothing itself.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "knit/recipes/stretch.hpp"

namespace knit {

/// The figures of a pull into options.out_dir: stretch_force.png and stretch_width.png
/// titled with `label` (where gnuplot is installed), and, when `ended`, options.render and
/// options.write_frames, the renders of the sample at strains 0, 0.25, 0.5 and 1 (those up to
/// to_strain, and to_strain itself) side by side in stretch_renders.png (each also as
/// `renders/strain_<e>.png`) and a movie of every frame in movie/animation.mp4. Returns the
/// summary's "renders" entry, or null when nothing was rendered.
nlohmann::json write_stretch_figures(const StretchOptions& options,
                                     const std::vector<StretchSample>& curve,
                                     const std::string& label, bool ended);

/// Draws the force–strain curves (moving clamp) of several stretch runs' directories in
/// one plot, each labelled "PATTERN DIRECTION, SPEED cm/s" from its summary. Returns the path
/// written.
std::string plot_stretch_runs(const std::vector<std::string>& dirs, const std::string& out_png);

}  // namespace knit
