#include "knit/io/states.hpp"

#include <algorithm>
#include <filesystem>
#include <stdexcept>

#include "knit/spline/fit.hpp"

namespace knit {

void check_state_file(const StateFile& f, const std::string& what) {
  if (f.yarn_cp_counts.empty()) throw std::invalid_argument(what + ": state has no yarns");
  if (f.yarn_radius.size() != f.yarn_cp_counts.size())
    throw std::invalid_argument(what + ": state has " + std::to_string(f.yarn_radius.size()) +
                                " radii for " + std::to_string(f.yarn_cp_counts.size()) + " yarns");
  for (size_t y = 0; y < f.yarn_cp_counts.size(); ++y)
    if (f.yarn_cp_counts[y] < 4)
      throw std::invalid_argument(what + ": yarn " + std::to_string(y) +
                                  " has fewer than 4 control points");
  if (f.state.q.size() != 3 * f.num_cp())
    throw std::invalid_argument(what + ": state holds " + std::to_string(f.state.q.size()) +
                                " coordinates, the yarn layout needs " +
                                std::to_string(3 * f.num_cp()));
  if (!f.stitch.empty() && static_cast<int>(f.stitch.size()) != f.num_seg())
    throw std::invalid_argument(what + ": stitch coordinates do not match the segments");
}

std::vector<Eigen::Matrix3Xd> yarn_control_points(const StateFile& f) {
  check_state_file(f, "state");
  std::vector<Eigen::Matrix3Xd> out;
  int begin = 0;
  for (int n : f.yarn_cp_counts) {
    out.push_back(Eigen::Map<const Eigen::Matrix3Xd>(f.state.q.data() + 3 * begin, 3, n));
    begin += n;
  }
  return out;
}

void check_state_sequence(const std::vector<StateFile>& frames, const std::vector<double>& times,
                          const std::string& what) {
  if (frames.empty()) throw std::invalid_argument(what + ": no states");
  if (times.size() != frames.size())
    throw std::invalid_argument(what + ": " + std::to_string(times.size()) + " times for " +
                                std::to_string(frames.size()) + " states");
  for (size_t f = 0; f < frames.size(); ++f) {
    check_state_file(frames[f], what + ": state " + std::to_string(f));
    if (frames[f].yarn_cp_counts != frames[0].yarn_cp_counts)
      throw std::invalid_argument(what + ": state " + std::to_string(f) +
                                  " has a different yarn layout from state 0");
    if (f > 0 && !(times[f] > times[f - 1]))
      throw std::invalid_argument(what + ": times must increase (state " + std::to_string(f) + ")");
  }
}

std::vector<Eigen::Matrix3Xd> sample_yarns(const StateFile& f, int per_segment) {
  std::vector<Eigen::Matrix3Xd> out;
  for (const auto& cp : yarn_control_points(f)) out.push_back(sample_bspline(cp, per_segment));
  return out;
}

StateFile state_from_yarns(const std::vector<ImportedYarn>& yarns) {
  StateFile f;
  int total = 0;
  for (const auto& y : yarns) total += static_cast<int>(y.control_points.cols());
  f.state.q.resize(3 * total);
  f.state.v = Eigen::VectorXd::Zero(3 * total);
  int begin = 0;
  for (const auto& y : yarns) {
    const int n = static_cast<int>(y.control_points.cols());
    Eigen::Map<Eigen::Matrix3Xd>(f.state.q.data() + 3 * begin, 3, n) = y.control_points;
    f.yarn_cp_counts.push_back(n);
    f.yarn_radius.push_back(y.radius);
    begin += n;
  }
  return f;
}

StateFile load_state(const std::string& path) {
  if (is_importable(path)) return state_from_yarns(import_yarns(path));
  return read_state_file(path);
}

std::vector<std::string> list_state_files(const std::string& dir) {
  namespace fs = std::filesystem;
  // a run directory (simulate/relax output) keeps its sequence under frames/
  std::error_code probe;
  if (fs::is_directory(fs::path(dir) / "frames", probe)) {
    for (const auto& e : fs::directory_iterator(fs::path(dir) / "frames", probe))
      if (e.is_regular_file() && e.path().extension() == ".kstate")
        return list_state_files((fs::path(dir) / "frames").string());
  }
  std::vector<std::string> files;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.is_regular_file() && e.path().extension() == ".kstate")
      files.push_back(e.path().string());
  if (ec) throw std::runtime_error(dir + ": cannot list directory: " + ec.message());
  if (files.empty()) throw std::runtime_error(dir + ": no .kstate files in the directory");
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace knit
