#pragma once
// Importing yarn geometry made by other tools and fitting it to knitsim's uniform cubic
// B-splines (MODEL.md §1).
//
// Readers (dispatch on the file extension):
//   .yarns  textiles-lab smobj chunked binary (chunks f3.., src., yarn, strs, unit, chk.);
//           carries a radius per yarn.
//   .bcc    Cem Yuksel's binary curve collection, curve types PL (polyline) and C0
//           (uniform Catmull-Rom); no radius.
//   .obj    Wavefront polylines (`v` and `l` statements); no radius.
//
// Every reader first produces RawYarn polylines in the file's own units; fit_yarns then
// scales them and fits each to a B-spline with fit_polyline. Corrupt input raises
// std::runtime_error naming the file, the chunk (or line) and the byte offset.
#include <Eigen/Core>
#include <string>
#include <string_view>
#include <vector>

#include "knit/model/params.hpp"

namespace knit {

/// A yarn ready for a ModelBuilder: control points (3×m, cm, m ≥ 4) and radius (cm).
struct ImportedYarn {
  Eigen::Matrix3Xd control_points;
  double radius = 0;
};

/// A polyline as stored in a file, in the file's units; radius ≤ 0 when the file has none.
struct RawYarn {
  Eigen::Matrix3Xd points;
  double radius = 0;
};

struct ImportOptions {
  /// Multiplies every coordinate and radius. 0 (default): choose so that the file's yarn
  /// radius (that of its first yarn) becomes `radius`; 1 when the file has no radius.
  double scale = 0;
  /// Yarn radius (cm) for files without one, and the target of the automatic scale.
  double radius = Material{}.radius;  // the material default
  /// Spline segments per cm of (scaled) yarn. 0 (default): 1 / (2.5 r), so a segment is
  /// about 2.5 radii long. For r = 0.125 cm that is 3.2 segments/cm, i.e. a 0.31 cm
  /// segment, which matches the paper's 8 segments per stitch loop of ≈ 2.5 cm of yarn.
  double segments_per_cm = 0;
  /// Refuse yarns that would need more segments than this (guards against absurd input).
  int max_segments = 1000000;
};

/// Reads any supported file and fits it. Throws std::runtime_error (naming the file) on
/// unreadable, corrupt or unsupported input.
std::vector<ImportedYarn> import_yarns(const std::string& path, const ImportOptions& options = {});

/// Scales and fits polylines (see ImportOptions). `name` is used in error messages.
std::vector<ImportedYarn> fit_yarns(const std::vector<RawYarn>& yarns, const ImportOptions& options,
                                    const std::string& name);

/// A yarn file's bytes (a regular file of at most MAX_GEOMETRY_BYTES).
std::string read_yarn_file(const std::string& path);

/// Parsers over a whole file's bytes; `name` is used in error messages.
std::vector<RawYarn> parse_yarns_file(std::string_view data, const std::string& name);
std::vector<RawYarn> parse_bcc(std::string_view data, const std::string& name);
std::vector<RawYarn> parse_obj(std::string_view data, const std::string& name);

/// Reads polylines from a file without fitting (its reader in the registry by extension,
/// formats.hpp).
std::vector<RawYarn> read_raw_yarns(const std::string& path);

/// true when `path` has an extension import_yarns understands (a format with a reader in
/// the registry, formats.hpp).
bool is_importable(const std::string& path);

/// Smallest distance between spline samples of segment pairs that MODEL.md §3 treats as
/// potential contacts (|i − j| > 1 on one yarn, any pair across yarns), divided by the
/// contact distance 2r (r: the larger radius of the pair). ≥ 1 means no tubes overlap.
/// `per_segment` samples per segment. Returns +inf when there are no such pairs.
double min_clearance(const std::vector<ImportedYarn>& yarns, int per_segment = 8);

}  // namespace knit
