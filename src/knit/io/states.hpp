#pragma once
// Helpers shared by the exporters, the renderer and the command-line tools: yarn geometry
// out of a StateFile, loading states (or importable yarn files) and listing a sequence.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "knit/io/import.hpp"
#include "knit/io/state_file.hpp"

namespace knit {

/// Throws std::invalid_argument (prefixed by `what`) when the state's arrays disagree
/// with its yarn layout or a yarn has fewer than 4 control points.
void check_state_file(const StateFile& file, const std::string& what);

/// Throws std::invalid_argument (prefixed by `what`) unless `frames` is a sequence one file
/// can hold: at least one state, a time for each, every state valid and with state 0's yarn
/// layout, times increasing.
void check_state_sequence(const std::vector<StateFile>& frames, const std::vector<double>& times,
                          const std::string& what);

/// Control points (3×m, cm) of every yarn.
std::vector<Eigen::Matrix3Xd> yarn_control_points(const StateFile& file);

/// Every yarn's spline sampled at `per_segment` points per segment plus its end point.
std::vector<Eigen::Matrix3Xd> sample_yarns(const StateFile& file, int per_segment);

/// A state at rest (zero velocity, time 0) holding imported yarns, without stitches.
StateFile state_from_yarns(const std::vector<ImportedYarn>& yarns);

/// Reads a .kstate file, or imports a .yarns/.bcc/.obj file with default options.
StateFile load_state(const std::string& path);

/// The .kstate files of a directory, sorted by name; for a run directory (one holding
/// frames/*.kstate) the frames. Throws when there are none.
std::vector<std::string> list_state_files(const std::string& dir);

}  // namespace knit
