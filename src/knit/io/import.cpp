#include "knit/io/import.hpp"

#include "knit/util/input_file.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "knit/spline/fit.hpp"

namespace knit {
namespace {}  // namespace

std::string read_yarn_file(const std::string& path) {
  return read_input_file(path, MAX_GEOMETRY_BYTES, "yarn geometry file");
}

std::vector<ImportedYarn> import_yarns(const std::string& path, const ImportOptions& options) {
  return fit_yarns(read_raw_yarns(path), options, path);
}

std::vector<ImportedYarn> fit_yarns(const std::vector<RawYarn>& yarns, const ImportOptions& options,
                                    const std::string& name) {
  if (yarns.empty()) throw std::runtime_error(name + ": no yarns");
  if (!(options.radius > 0)) throw std::invalid_argument(name + ": import radius must be > 0");
  if (options.scale < 0 || !std::isfinite(options.scale))
    throw std::invalid_argument(name + ": import scale must be > 0 (or 0 for automatic)");
  const double file_radius = yarns.front().radius;
  double scale = options.scale;
  if (scale == 0) scale = file_radius > 0 ? options.radius / file_radius : 1.0;
  std::vector<ImportedYarn> out;
  for (size_t y = 0; y < yarns.size(); ++y) {
    const RawYarn& raw = yarns[y];
    const std::string which = name + ": yarn " + std::to_string(y);
    ImportedYarn yarn;
    yarn.radius = raw.radius > 0 ? raw.radius * scale : options.radius;
    const Eigen::Matrix3Xd pts = raw.points * scale;
    if (pts.cols() < 2) throw std::runtime_error(which + " has fewer than 2 points");
    if (!pts.allFinite()) throw std::runtime_error(which + " has non-finite coordinates");
    const double length = polyline_length(pts);
    if (!(length > 0) || !std::isfinite(length))
      throw std::runtime_error(which + " has zero or non-finite length");
    const double per_cm =
        options.segments_per_cm > 0 ? options.segments_per_cm : 1.0 / (2.5 * yarn.radius);
    const double want = std::round(length * per_cm);
    if (!(want <= options.max_segments))
      throw std::runtime_error(which + " would need " + short_number(want) +
                               " spline segments (length " + short_number(length) +
                               " cm), more than the limit of " +
                               std::to_string(options.max_segments));
    const int segments = std::max(1, static_cast<int>(want));
    yarn.control_points = fit_polyline(pts, segments);
    if (!yarn.control_points.allFinite())
      throw std::runtime_error(which + ": spline fit failed (degenerate polyline?)");
    out.push_back(std::move(yarn));
  }
  return out;
}

double min_clearance(const std::vector<ImportedYarn>& yarns, int per_segment) {
  struct Seg {
    int yarn, local;
    double radius;
    Eigen::Vector3d centre;
    double bound;  // radius of a sphere around centre holding every sample
    Eigen::Matrix3Xd samples;
  };
  std::vector<Seg> segs;
  for (size_t y = 0; y < yarns.size(); ++y) {
    const Eigen::Matrix3Xd& cp = yarns[y].control_points;
    const Eigen::Matrix3Xd s = sample_bspline(cp, per_segment);
    for (int i = 0; i + 3 < cp.cols(); ++i) {
      Seg seg{static_cast<int>(y),
              i,
              yarns[y].radius,
              {},
              0,
              s.middleCols(i * per_segment, per_segment + 1)};
      seg.centre = seg.samples.rowwise().mean();
      seg.bound = (seg.samples.colwise() - seg.centre).colwise().norm().maxCoeff();
      segs.push_back(std::move(seg));
    }
  }
  // sweep along x so far-apart segments are never compared
  std::sort(segs.begin(), segs.end(), [](const Seg& a, const Seg& b) {
    return a.centre.x() - a.bound < b.centre.x() - b.bound;
  });
  double max_radius = 0;
  for (const Seg& s : segs) max_radius = std::max(max_radius, s.radius);
  double best = std::numeric_limits<double>::infinity();  // in units of 2r
  for (size_t a = 0; a < segs.size(); ++a) {
    const Seg& A = segs[a];
    for (size_t b = a + 1; b < segs.size(); ++b) {
      const Seg& B = segs[b];
      const double gap_x = (B.centre.x() - B.bound) - (A.centre.x() + A.bound);
      if (gap_x > 0 && gap_x / (2 * max_radius) >= best) break;
      if (A.yarn == B.yarn && std::abs(A.local - B.local) <= 1) continue;
      const double two_r = 2 * std::max(A.radius, B.radius);
      const double lower = (A.centre - B.centre).norm() - A.bound - B.bound;
      if (lower / two_r >= best) continue;
      for (Eigen::Index i = 0; i < A.samples.cols(); ++i) {
        const double d = (B.samples.colwise() - A.samples.col(i)).colwise().norm().minCoeff();
        best = std::min(best, d / two_r);
      }
    }
  }
  return best;
}

}  // namespace knit
