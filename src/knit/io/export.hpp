#pragma once
// Exporting states to other tools. Every writer builds the whole file in memory and
// writes it with write_file_atomic, so an output is never half-written.
//
//   USD (.usda text)  exact curves: one BasisCurves prim per yarn (cubic, bspline,
//                     nonperiodic), control points as `points`, per-point widths = 2r,
//                     displayColor by stitch row (by yarn without stitches), velocities
//                     (cm/s) for motion blur; a sequence of states becomes one file with
//                     time samples. Z up, 1 unit = 1 cm.
//                     A scene's solid objects follow as one Mesh prim each (their surface,
//                     triangulated in the object's frame; a plane as a slab around the
//                     yarn), placed by translate and orient ops, time-sampled when they move.
//   OBJ               polylines (`v`, and `l` for each span), splines sampled densely.
//   BCC               Cem Yuksel's binary curve collection, PL (polyline) curves.
//   PLY               points and edges (binary little-endian or ascii).
//   VTP               VTK XML PolyData for ParaView: one polyline per yarn and per-point
//                     arrays radius, yarn, row, column (−1 off the stitches), velocity.
//   Tube meshes (OBJ, PLY, glTF) for viewers without curves: tube_mesh.hpp.
#include <memory>
#include <string>
#include <vector>

#include "knit/io/state_file.hpp"
#include "knit/io/tube_mesh.hpp"
#include "knit/objects/object.hpp"
#include "knit/util/atomic_file.hpp"

namespace knit {

/// Default number of polyline samples per spline segment for the sampled formats.
inline constexpr int EXPORT_SAMPLES_PER_SEGMENT = 8;

/// The text of a .usda file for `frames` at `times` (s, one per frame, increasing). With one
/// frame the points are plain values; with several, time samples (time code = frame
/// index; timeCodesPerSecond from the mean frame spacing). All frames need the same yarn
/// layout. Throws std::invalid_argument otherwise.
/// `objects` (a scene's) are written after the yarns.
std::string usda_text(const std::vector<StateFile>& frames, const std::vector<double>& times,
                      const std::vector<std::shared_ptr<const SceneObject>>& objects = {});
void export_usd(const std::vector<StateFile>& frames, const std::vector<double>& times,
                const std::string& path,
                const std::vector<std::shared_ptr<const SceneObject>>& objects = {});

/// OBJ polylines: one object per yarn, `per_segment` samples per spline segment.
std::string obj_text(const StateFile& state, int per_segment = EXPORT_SAMPLES_PER_SEGMENT);
void export_obj(const StateFile& state, const std::string& path,
                int per_segment = EXPORT_SAMPLES_PER_SEGMENT);

/// BCC polylines (PL), one curve per yarn: the file's bytes.
std::string bcc_text(const StateFile& state, int per_segment = EXPORT_SAMPLES_PER_SEGMENT);
void export_bcc(const StateFile& state, const std::string& path,
                int per_segment = EXPORT_SAMPLES_PER_SEGMENT);

/// PLY with vertex x, y, z (float), yarn (int), radius (float) and edge vertex1, vertex2.
std::string ply_bytes(const StateFile& state, bool binary,
                      int per_segment = EXPORT_SAMPLES_PER_SEGMENT);
void export_ply(const StateFile& state, const std::string& path, bool binary = true,
                int per_segment = EXPORT_SAMPLES_PER_SEGMENT);

/// VTK XML PolyData (ascii): the sampled centrelines as one polyline cell per yarn, with
/// point data radius (cm), yarn, row and column (of the segment each sample lies on; −1
/// without stitch coordinates) and velocity (cm/s, the spline of the control-point
/// velocities), and the state's time as field data TimeValue.
std::string vtp_text(const StateFile& state, int per_segment = EXPORT_SAMPLES_PER_SEGMENT);
void export_vtp(const StateFile& state, const std::string& path,
                int per_segment = EXPORT_SAMPLES_PER_SEGMENT);

/// The name of every format export_state writes, in the registry's order (formats.hpp).
const std::vector<std::string>& export_formats();
/// The file name extension `format` writes (".usda", ".obj", ".ply", ".glb", ...).
/// Throws std::invalid_argument for a format not in export_formats().
std::string export_extension(const std::string& format);

struct ExportOptions {
  int samples = EXPORT_SAMPLES_PER_SEGMENT;  ///< polyline samples per spline segment
  int sides = TUBE_SIDES;                    ///< tube mesh sides
  bool binary_ply = true;                    ///< ply: binary little-endian, else ascii
  /// usd: a scene's objects, written after the yarns
  std::vector<std::shared_ptr<const SceneObject>> objects;
};

/// Writes one state in `format` (one of export_formats(); its writer in the registry,
/// formats.hpp) to `path`, atomically.
/// Throws std::invalid_argument for an unknown format or bad options.
void export_state(const StateFile& state, const std::string& format, const std::string& path,
                  const ExportOptions& options = {});

}  // namespace knit
