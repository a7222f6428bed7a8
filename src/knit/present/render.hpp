#pragma once
// Ray tracing of the exact yarn tubes with Embree 3 round B-spline curves (the same
// uniform cubic B-spline as MODEL.md §1, swept by a sphere of the yarn radius).
//
// The camera is framed on a bounding box. Views are defined relative to the box's
// thinnest axis n (the normal of a swatch): `front` looks at the face on the +n side,
// `back` at the −n side, `side` along the swatch from its right edge, `iso` from above
// the front-right. The image's up direction is +z, or +y when n is z (a swatch lying in
// the xy plane). `scene` ignores the box's shape and looks at the world as it stands (+z up,
// from the front-right and above): the view for a knit among objects under gravity. A key light
// from the upper left casts soft shadows (several rays to an area light), ambient occlusion darkens
// crevices, pixels are supersampled with jittered samples, and a backdrop plane sits behind the
// cloth to catch its shadow. Rendering is parallel over image tiles (TBB); results do not depend on
// the thread count.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "knit/io/state_file.hpp"
#include "knit/objects/object.hpp"

namespace knit {

enum class View { FRONT, BACK, SIDE, ISO, SCENE };

/// Parses front|back|side|iso|scene (throws std::invalid_argument naming the value otherwise).
View parse_view(const std::string& name);

/// An 8-bit sRGB image, rows top to bottom, and per pixel the fraction of samples that
/// hit a yarn (for tests and compositing).
struct Image {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;     ///< 3·width·height
  std::vector<float> coverage;  ///< width·height, in [0,1]; may be empty
  Image() = default;
  Image(int w, int h, Eigen::Vector3f fill = Eigen::Vector3f::Ones());
  Eigen::Vector3f pixel(int x, int y) const;  ///< RGB in [0,1]
  void set_pixel(int x, int y, const Eigen::Vector3f& c);
};

/// A pinhole camera: the ray through image point (px, py) (pixel units, origin at the top
/// left corner of the image) starts at `eye` with direction `direction(px, py)`.
struct Camera {
  Eigen::Vector3d eye, forward, right, up;
  double tan_half_x = 0, tan_half_y = 0;
  int width = 0, height = 0;
  Eigen::Vector3d direction(double px, double py) const;
};

/// A camera that sees all of `box` (cm) from `view` with a small margin.
Camera frame_camera(const Eigen::AlignedBox3d& box, View view, int width, int height);

/// Bounding box of every yarn tube (control-point box grown by the radius; it holds the
/// spline by the convex-hull property).
Eigen::AlignedBox3d state_bounds(const StateFile& state);

struct RenderOptions {
  int width = 1024, height = 768;
  View view = View::FRONT;
  bool color_rows = false;  ///< alternate colours by stitch row (needs stitch data)
  int spp = 4;              ///< jittered camera samples per pixel
  int shadow_rays = 4;      ///< soft-shadow rays per camera sample
  int ao_rays = 4;          ///< ambient-occlusion rays per camera sample
  bool backdrop = true;     ///< a plane behind the cloth that catches its shadow
  /// Box the camera frames; default: state_bounds (give the same box to every frame of
  /// an animation or every panel of a comparison so their scale matches).
  std::optional<Eigen::AlignedBox3d> frame;
  /// Solid objects drawn under the yarn at the state's time (their surfaces where they lie
  /// within the framed box grown by half its largest side: a plane is drawn as a slab that
  /// wide).
  std::vector<std::shared_ptr<const SceneObject>> objects;
  /// A scale bar in the bottom right corner: a round length (1, 2 or 5 × 10^k cm) at most
  /// a quarter of the image wide, measured at the depth of the framed box's centre, and
  /// its length written above it.
  bool scale_bar = false;
  /// Text in the bottom left corner (e.g. the state's time); empty: none.
  std::string caption;
};

/// The scale bar render_state draws: its length (cm) and width (pixels) for `camera`
/// looking at a box centred at `centre`.
std::pair<double, int> scale_bar_length(const Camera& camera, const Eigen::Vector3d& centre);

/// The box a camera should frame for `state` among `objects`: the yarn's bounds and the
/// bounds of every bounded object at the state's time.
Eigen::AlignedBox3d scene_bounds(const StateFile& state,
                                 const std::vector<std::shared_ptr<const SceneObject>>& objects);

/// Renders the yarns of `state`. Throws std::invalid_argument on bad options or state.
Image render_state(const StateFile& state, const RenderOptions& options);

/// Writes a PNG atomically. Throws std::runtime_error on failure.
void write_png(const Image& image, const std::string& path);

/// Draws `text` (UTF-8; '\n' starts a new line) anti-aliased in DejaVu Sans with FreeType,
/// `pixel_height` pixels per line, its top left corner at (x, y), clipped to the image.
/// The font is looked up once: $KNIT_FONT, else Debian's fonts-dejavu-core; without it
/// the text is drawn in a built-in bitmap font (stb_easy_font, ASCII only) and a warning
/// is printed once.
void draw_text(Image& image, int x, int y, const std::string& text, int pixel_height,
               const Eigen::Vector3f& color);
/// Width and height in image pixels of `text` drawn at `pixel_height`.
Eigen::Vector2i text_size(const std::string& text, int pixel_height);
/// The TrueType font labels are drawn with, or "" when the bitmap fallback is in use.
std::string label_font_path();

/// Places images side by side (equal heights expected) on a white strip, each with its
/// label centred beneath it (labels may be empty).
Image compose_side_by_side(const std::vector<Image>& images,
                           const std::vector<std::string>& labels);

}  // namespace knit
