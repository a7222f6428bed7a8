#pragma once
// A run in the browser: one self-contained HTML page (three.js inlined, the states' control
// points embedded) that plays the frames as shaded yarn tubes with orbit controls, a time
// slider and a play button, and opens offline with a double click.
//
// three.js comes from Debian's libjs-three (/usr/share/javascript/three: three.min.js and
// examples/js/controls/OrbitControls.js), read when the page is written.
// The page evaluates each yarn's exact cubic B-spline from its control points, samples it
// and sweeps a tube around it (as tube_mesh.hpp does), coloured by stitch row (by yarn
// without stitches). A scene's solid objects are drawn in grey at each frame's time, as
// `knitsim render` draws them: their surfaces (objects/mesh_shape.hpp's surface_mesh) where
// they lie within the framed box grown by half its largest side, so a floor is a slab that
// wide. The camera frames every frame's yarn and bounded objects. A scale bar in the bottom
// right corner (a round length, 1, 2 or 5 × 10^k cm, at most a quarter of the view wide,
// measured at the depth of the orbit's centre) follows every zoom and orbit. It plays at the
// simulation's real time by default. `#frame=N` in the page's address opens it at frame N (as
// moving the slider there does), `#zoom=Z` (with `&` after a frame) Z times closer.
//
// The page's script is src/knit/present/viewer.js. For tests and tools, the page reports what it
// drew in its DOM: <body data-objects="N"> (the objects drawn) and the scale bar's
// <div id="scale" data-cm="L" data-px-per-cm="P" data-view="WxH"> (WxH: the
// picture's size in CSS pixels, for which P holds).
#include <memory>
#include <string>
#include <vector>

#include "knit/io/state_file.hpp"
#include "knit/objects/object.hpp"

namespace knit {

/// Where Debian's libjs-three installs three.js.
inline constexpr const char* THREE_JS_DIR = "/usr/share/javascript/three";

struct ViewerOptions {
  std::string title = "knitsim";
  std::string three_dir = THREE_JS_DIR;  ///< three.min.js and examples/js/controls/
  int samples_per_segment = 4;           ///< points along each spline segment
  int sides = 8;                         ///< vertices around the tube
  /// Largest page written (bytes): a long run's frames can be many; thin them (every Nth).
  long long max_bytes = 400ll << 20;
  /// A scene's solid objects, drawn with the yarn (their surfaces count towards max_bytes).
  std::vector<std::shared_ptr<const SceneObject>> objects;
};

/// The page for `frames` at `times` (s, increasing; one frame is a still). All frames need
/// the same yarn layout. Throws std::invalid_argument for bad frames or options (naming the
/// frame), std::runtime_error when three.js is missing (naming the package) or the page
/// would exceed max_bytes.
std::string viewer_html(const std::vector<StateFile>& frames, const std::vector<double>& times,
                        const ViewerOptions& options = {});

}  // namespace knit
