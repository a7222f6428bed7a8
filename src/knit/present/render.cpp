#include "knit/present/render.hpp"

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <stdexcept>

#include "knit/io/states.hpp"
#include "knit/objects/mesh_shape.hpp"
#include "knit/spline/basis.hpp"

namespace knit {
namespace {

using Vec3 = Eigen::Vector3d;
using Col = Eigen::Vector3f;

constexpr double PI = 3.14159265358979323846;
constexpr unsigned CURVES_ID = 0, BACKDROP_ID = 1, CAPS_ID = 2, OBJECTS_ID = 3;

// sRGB ↔ linear
float srgb_to_linear(float c) {
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}
float linear_to_srgb(float c) {
  c = std::clamp(c, 0.0f, 1.0f);
  return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}
Col hex_colour(unsigned rgb) {
  return Col(srgb_to_linear(((rgb >> 16) & 255) / 255.0f),
             srgb_to_linear(((rgb >> 8) & 255) / 255.0f), srgb_to_linear((rgb & 255) / 255.0f));
}

// yarn colours: cream, rust, teal, mustard, plum, sage, slate blue
const unsigned YARN_PALETTE[] = {0xE6D8BC, 0xB4533C, 0x2F7074, 0xD4A03F,
                                 0x77506F, 0x8BA57C, 0x4A6183};
// alternating rows of a striped swatch: cream and deep teal; segments off the fabric grey
const unsigned ROW_PALETTE[] = {0xEDE2CB, 0x2C6A70};
const unsigned OFF_FABRIC = 0x9A9590;

// deterministic per-sample random numbers (thread-count independent)
struct Rng {
  uint64_t s;
  explicit Rng(uint64_t seed) : s(seed * 0x9E3779B97F4A7C15ull + 0x632BE59BD9B4E019ull) { next(); }
  uint64_t next() {
    s ^= s >> 12;
    s ^= s << 25;
    s ^= s >> 27;
    return s * 0x2545F4914F6CDD1Dull;
  }
  double uniform() { return (next() >> 11) * (1.0 / 9007199254740992.0); }
};

void orthonormal_basis(const Vec3& n, Vec3& a, Vec3& b) {
  a = (std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).cross(n).normalized();
  b = n.cross(a);
}

struct EmbreeDevice {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  EmbreeDevice() {
    device = rtcNewDevice(nullptr);
    if (!device) throw std::runtime_error("render: cannot create an Embree device");
  }
  ~EmbreeDevice() {
    if (scene) rtcReleaseScene(scene);
    rtcReleaseDevice(device);
  }
  EmbreeDevice(const EmbreeDevice&) = delete;
  EmbreeDevice& operator=(const EmbreeDevice&) = delete;
};

// the three camera axes of a view (forward, up hint) for a box with thin axis n
void view_axes(const Eigen::AlignedBox3d& box, View view, Vec3& forward, Vec3& up) {
  const Vec3 ext = box.sizes();
  int thin = 0;
  for (int k = 1; k < 3; ++k)
    if (ext[k] < ext[thin]) thin = k;
  const Vec3 n = Vec3::Unit(thin);
  up = thin == 2 ? Vec3::UnitY() : Vec3::UnitZ();
  const Vec3 front_right = (-n).cross(up);  // image right when looking at the front
  switch (view) {
    case View::FRONT:
      forward = -n;
      break;
    case View::BACK:
      forward = n;
      break;
    case View::SIDE:
      forward = -front_right;
      break;
    case View::ISO:
      forward = -(n + 0.65 * front_right + 0.55 * up).normalized();
      break;
    case View::SCENE:
      // the world as it stands: +z up, seen from the front (−y), right (+x) and above
      up = Vec3::UnitZ();
      forward = -Vec3(0.5, -1, 0.6).normalized();
      break;
  }
}

}  // namespace

View parse_view(const std::string& name) {
  if (name == "front") return View::FRONT;
  if (name == "back") return View::BACK;
  if (name == "side") return View::SIDE;
  if (name == "iso") return View::ISO;
  if (name == "scene") return View::SCENE;
  throw std::invalid_argument("unknown view '" + name +
                              "' (expected front, back, side, iso or scene)");
}

Vec3 Camera::direction(double px, double py) const {
  const double sx = (2.0 * px / width - 1.0) * tan_half_x;
  const double sy = (1.0 - 2.0 * py / height) * tan_half_y;
  return (forward + sx * right + sy * up).normalized();
}

Camera frame_camera(const Eigen::AlignedBox3d& box, View view, int width, int height) {
  if (width <= 0 || height <= 0) throw std::invalid_argument("render: image size must be positive");
  if (box.isEmpty()) throw std::invalid_argument("render: nothing to frame (empty box)");
  Camera cam;
  Vec3 up_hint;
  view_axes(box, view, cam.forward, up_hint);
  cam.right = cam.forward.cross(up_hint).normalized();
  cam.up = cam.right.cross(cam.forward);
  cam.width = width;
  cam.height = height;
  const double fovy = 30.0 * PI / 180.0;
  cam.tan_half_y = std::tan(fovy / 2);
  cam.tan_half_x = cam.tan_half_y * width / height;
  // the nearest eye distance at which every box corner projects inside the margin
  const double margin = 0.92;
  const Vec3 centre = box.center();
  double dist = 1e-6 + box.sizes().norm() * 0.01;
  for (int c = 0; c < 8; ++c) {
    const Vec3 d = box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c)) - centre;
    const double depth = d.dot(cam.forward);
    dist = std::max(dist, std::abs(d.dot(cam.right)) / (cam.tan_half_x * margin) - depth);
    dist = std::max(dist, std::abs(d.dot(cam.up)) / (cam.tan_half_y * margin) - depth);
  }
  cam.eye = centre - dist * cam.forward;
  return cam;
}

Eigen::AlignedBox3d state_bounds(const StateFile& state) {
  Eigen::AlignedBox3d box;
  const auto cps = yarn_control_points(state);
  for (size_t y = 0; y < cps.size(); ++y) {
    const Vec3 r = Vec3::Constant(state.yarn_radius[y]);
    box.extend(Vec3(cps[y].rowwise().minCoeff() - r));
    box.extend(Vec3(cps[y].rowwise().maxCoeff() + r));
  }
  return box;
}

Eigen::AlignedBox3d scene_bounds(const StateFile& state,
                                 const std::vector<std::shared_ptr<const SceneObject>>& objects) {
  Eigen::AlignedBox3d box = state_bounds(state);
  for (const auto& o : objects) {
    const Eigen::AlignedBox3d local = o->shape->bounds();
    if (!local.diagonal().allFinite()) continue;
    const ObjectFrame f(*o, state.state.time);
    for (int c = 0; c < 8; ++c)
      box.extend(f.to_world(local.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c))));
  }
  return box;
}

std::pair<double, int> scale_bar_length(const Camera& camera, const Eigen::Vector3d& centre) {
  // a pinhole camera: at depth d, one pixel spans 2 d tan(½ fov) / width
  const double depth = std::max((centre - camera.eye).dot(camera.forward), 1e-9);
  const double px_per_cm = camera.width / (2 * depth * camera.tan_half_x);
  double length = 0;
  for (double decade = 1e-3; decade <= 1e4; decade *= 10)
    for (double m : {1.0, 2.0, 5.0})
      if (m * decade * px_per_cm <= 0.25 * camera.width) length = m * decade;
  return {length, static_cast<int>(std::lround(length * px_per_cm))};
}

namespace {

std::string format_length(double cm) {
  char buf[32];
  if (cm >= 1)
    std::snprintf(buf, sizeof buf, "%g cm", cm);
  else
    std::snprintf(buf, sizeof buf, "%g mm", cm * 10);
  return buf;
}

// the scale bar and caption of RenderOptions, in dark grey, sized to the image
void annotate(Image& image, const RenderOptions& opt, const Camera& cam,
              const Eigen::Vector3d& centre) {
  const int scale = std::max(1, std::min(image.width, image.height) / 240);
  const int px = std::max(12, std::min(image.width, image.height) / 30);  // text height
  const int margin = 6 * scale;
  const Eigen::Vector3f ink(0.15f, 0.15f, 0.17f);
  if (opt.scale_bar) {
    const auto [length, pixels] = scale_bar_length(cam, centre);
    if (length > 0 && pixels >= 4) {
      const int x1 = image.width - margin, x0 = x1 - pixels;
      const int y1 = image.height - margin, y0 = y1 - 2 * scale;
      for (int y = y0; y < y1; ++y)
        for (int x = std::max(x0, 0); x < x1; ++x) image.set_pixel(x, y, ink);
      // end ticks
      for (int y = y0 - 3 * scale; y < y1; ++y)
        for (int t = 0; t < scale; ++t) {
          if (x0 + t >= 0) image.set_pixel(x0 + t, y, ink);
          image.set_pixel(x1 - 1 - t, y, ink);
        }
      const std::string label = format_length(length);
      const Eigen::Vector2i size = text_size(label, px);
      draw_text(image, x1 - size.x(), y0 - 3 * scale - size.y(), label, px, ink);
    }
  }
  if (!opt.caption.empty()) {
    const Eigen::Vector2i size = text_size(opt.caption, px);
    draw_text(image, margin, image.height - margin - size.y(), opt.caption, px, ink);
  }
}

}  // namespace

Image render_state(const StateFile& state, const RenderOptions& opt) {
  check_state_file(state, "render");
  if (!state.state.q.allFinite())
    throw std::invalid_argument("render: state has non-finite positions");
  if (opt.width <= 0 || opt.height <= 0 || opt.width > 16384 || opt.height > 16384)
    throw std::invalid_argument("render: image size must be between 1 and 16384 pixels");
  if (opt.spp < 1 || opt.shadow_rays < 0 || opt.ao_rays < 0)
    throw std::invalid_argument("render: need spp >= 1 and non-negative shadow and AO rays");

  const Eigen::AlignedBox3d bounds = state_bounds(state);
  const Eigen::AlignedBox3d frame =
      opt.frame.value_or(opt.objects.empty() ? bounds : scene_bounds(state, opt.objects));
  const Camera cam = frame_camera(frame, opt.view, opt.width, opt.height);
  const double diag = frame.sizes().norm();
  double max_radius = 0;
  for (double r : state.yarn_radius) max_radius = std::max(max_radius, r);
  const double eps = 1e-4 * diag;

  // per segment: first control point (global) and colour
  const int nseg = state.num_seg();
  std::vector<int> seg_cp(nseg), seg_yarn(nseg);
  std::vector<Col> seg_colour(nseg);
  const bool rows = opt.color_rows && !state.stitch.empty();
  {
    int s = 0, cp = 0;
    for (size_t y = 0; y < state.yarn_cp_counts.size(); ++y) {
      const Col yarn_col = hex_colour(YARN_PALETTE[y % std::size(YARN_PALETTE)]);
      for (int i = 0; i + 3 < state.yarn_cp_counts[y]; ++i, ++s) {
        seg_cp[s] = cp + i;
        seg_yarn[s] = static_cast<int>(y);
        if (rows) {
          const int row = state.stitch[s].row;
          seg_colour[s] = row < 0 ? hex_colour(OFF_FABRIC) : hex_colour(ROW_PALETTE[row % 2]);
        } else {
          seg_colour[s] = yarn_col;
        }
      }
      cp += state.yarn_cp_counts[y];
    }
  }

  // a twisted-ply texture needs a frame around each yarn that varies smoothly: a
  // reference normal parallel-transported from segment to segment, and the arclength
  struct SegFrame {
    Vec3 ref;
    double s0 = 0, length = 0;
  };
  std::vector<SegFrame> seg_frame(nseg);
  auto seg_point = [&](int seg, double t) -> Vec3 {
    const Eigen::Vector4d b = bspline_basis(t);
    Vec3 p = Vec3::Zero();
    for (int a = 0; a < 4; ++a) p += b[a] * state.state.q.segment<3>(3 * (seg_cp[seg] + a));
    return p;
  };
  auto seg_tangent = [&](int seg, double t) -> Vec3 {
    const Eigen::Vector4d db = bspline_basis_d1(t);
    Vec3 d = Vec3::Zero();
    for (int a = 0; a < 4; ++a) d += db[a] * state.state.q.segment<3>(3 * (seg_cp[seg] + a));
    return d.norm() > 0 ? Vec3(d.normalized()) : Vec3::UnitX();
  };
  {
    int s = 0;
    for (size_t y = 0; y < state.yarn_cp_counts.size(); ++y) {
      double arclength = 0;
      Vec3 ref, unused;
      orthonormal_basis(seg_tangent(s, 0), ref, unused);
      for (int i = 0; i + 3 < state.yarn_cp_counts[y]; ++i, ++s) {
        const Vec3 t = seg_tangent(s, 0);
        const Vec3 projected = ref - ref.dot(t) * t;
        if (projected.norm() > 1e-9) ref = projected.normalized();
        double len = 0;
        for (int k = 0; k < 8; ++k)
          len += (seg_point(s, (k + 1) / 8.0) - seg_point(s, k / 8.0)).norm();
        seg_frame[s] = {ref, arclength, len};
        arclength += len;
      }
    }
  }

  // scene: one round B-spline curve geometry for all yarns, end caps (+ the backdrop)
  EmbreeDevice dev;
  dev.scene = rtcNewScene(dev.device);
  rtcSetSceneBuildQuality(dev.scene, RTC_BUILD_QUALITY_HIGH);
  {
    RTCGeometry geom = rtcNewGeometry(dev.device, RTC_GEOMETRY_TYPE_ROUND_BSPLINE_CURVE);
    const int ncp = state.num_cp();
    auto* vtx = static_cast<float*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float), ncp));
    auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT, sizeof(unsigned), nseg));
    int cp = 0;
    for (size_t y = 0; y < state.yarn_cp_counts.size(); ++y)
      for (int k = 0; k < state.yarn_cp_counts[y]; ++k, ++cp) {
        for (int c = 0; c < 3; ++c) vtx[4 * cp + c] = static_cast<float>(state.state.q[3 * cp + c]);
        vtx[4 * cp + 3] = static_cast<float>(state.yarn_radius[y]);
      }
    for (int s = 0; s < nseg; ++s) idx[s] = static_cast<unsigned>(seg_cp[s]);
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(dev.scene, geom, CURVES_ID);
    rtcReleaseGeometry(geom);
  }
  // Embree leaves the tube open at a curve's ends: close each yarn end with a sphere of
  // the yarn radius (the exact sweep of the tube's sphere)
  std::vector<int> cap_seg;  // segment each cap belongs to
  {
    const int ncap = 2 * static_cast<int>(state.yarn_cp_counts.size());
    RTCGeometry geom = rtcNewGeometry(dev.device, RTC_GEOMETRY_TYPE_SPHERE_POINT);
    auto* vtx = static_cast<float*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float), ncap));
    int first = 0;
    for (size_t y = 0; y < state.yarn_cp_counts.size(); ++y) {
      const int last = first + state.yarn_cp_counts[y] - 4;
      const Vec3 ends[2] = {seg_point(first, 0), seg_point(last, 1)};
      for (int e = 0; e < 2; ++e) {
        const int c = 2 * static_cast<int>(y) + e;
        for (int d = 0; d < 3; ++d) vtx[4 * c + d] = static_cast<float>(ends[e][d]);
        vtx[4 * c + 3] = static_cast<float>(state.yarn_radius[y]);
        cap_seg.push_back(e == 0 ? first : last);
      }
      first = last + 1;
    }
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(dev.scene, geom, CAPS_ID);
    rtcReleaseGeometry(geom);
  }
  if (!opt.objects.empty()) {
    // the objects' surfaces at the state's time, within the frame grown by half its
    // largest side in every direction (a floor is drawn as a square slab under a tall knit)
    Eigen::AlignedBox3d region = frame;
    region.min().array() -= 0.5 * frame.sizes().maxCoeff();
    region.max().array() += 0.5 * frame.sizes().maxCoeff();
    std::vector<float> vertices;
    std::vector<unsigned> indices;
    for (const auto& o : opt.objects) {
      const TriangleMesh m =
          object_surface(*o, state.state.time, region, region.sizes().norm() / 240);
      const unsigned base = static_cast<unsigned>(vertices.size() / 3);
      for (const Vec3& v : m.vertices)
        for (int d = 0; d < 3; ++d) vertices.push_back(static_cast<float>(v[d]));
      for (const Eigen::Vector3i& t : m.triangles)
        for (int d = 0; d < 3; ++d) indices.push_back(base + static_cast<unsigned>(t[d]));
    }
    if (!indices.empty()) {
      RTCGeometry geom = rtcNewGeometry(dev.device, RTC_GEOMETRY_TYPE_TRIANGLE);
      auto* vtx = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0,
                                                              RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                              vertices.size() / 3));
      auto* tri = static_cast<unsigned*>(
          rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                  3 * sizeof(unsigned), indices.size() / 3));
      std::copy(vertices.begin(), vertices.end(), vtx);
      std::copy(indices.begin(), indices.end(), tri);
      rtcCommitGeometry(geom);
      rtcAttachGeometryByID(dev.scene, geom, OBJECTS_ID);
      rtcReleaseGeometry(geom);
    }
  }
  if (opt.backdrop) {
    // plane across the axis the camera looks along most, behind the cloth
    int k = 0;
    for (int c = 1; c < 3; ++c)
      if (std::abs(cam.forward[c]) > std::abs(cam.forward[k])) k = c;
    const double offset = 0.02 * diag + 4 * max_radius;
    const double plane = cam.forward[k] > 0 ? frame.max()[k] + offset : frame.min()[k] - offset;
    const int a = (k + 1) % 3, b = (k + 2) % 3;
    const double half = 50 * diag;
    const Vec3 c = frame.center();
    RTCGeometry geom = rtcNewGeometry(dev.device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vtx = static_cast<float*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), 4));
    auto* tri = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), 2));
    const double sa[4] = {-1, 1, 1, -1}, sb[4] = {-1, -1, 1, 1};
    for (int v = 0; v < 4; ++v) {
      Vec3 p;
      p[k] = plane;
      p[a] = c[a] + sa[v] * half;
      p[b] = c[b] + sb[v] * half;
      for (int d = 0; d < 3; ++d) vtx[3 * v + d] = static_cast<float>(p[d]);
    }
    const unsigned ids[6] = {0, 1, 2, 0, 2, 3};
    std::copy(ids, ids + 6, tri);
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(dev.scene, geom, BACKDROP_ID);
    rtcReleaseGeometry(geom);
  }
  rtcCommitScene(dev.scene);
  if (rtcGetDeviceError(dev.device) != RTC_ERROR_NONE)
    throw std::runtime_error("render: Embree could not build the scene");

  // lighting: a key light from the upper left of the camera, a sky for ambient light
  const Vec3 light = (-0.8 * cam.forward + 0.75 * cam.up - 0.55 * cam.right).normalized();
  Vec3 light_a, light_b;
  orthonormal_basis(light, light_a, light_b);
  const double light_spread = std::tan(0.035);  // angular radius of the area light (rad)
  const float sun = 1.0f, sky = 0.5f;
  const double ao_distance = 6 * max_radius;
  const Col backdrop_colour = hex_colour(0x8A949C);
  const Col object_colour = hex_colour(0x9AA7B2);

  auto occluded = [&](const Vec3& org, const Vec3& dir, double tfar) {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRay ray;
    ray.org_x = static_cast<float>(org.x());
    ray.org_y = static_cast<float>(org.y());
    ray.org_z = static_cast<float>(org.z());
    ray.dir_x = static_cast<float>(dir.x());
    ray.dir_y = static_cast<float>(dir.y());
    ray.dir_z = static_cast<float>(dir.z());
    ray.tnear = static_cast<float>(eps);
    ray.tfar = static_cast<float>(tfar);
    ray.time = 0;
    ray.mask = ~0u;
    ray.id = 0;
    ray.flags = 0;
    rtcOccluded1(dev.scene, &ctx, &ray);
    return ray.tfar < 0;
  };

  // radiance along one camera ray; `hit_yarn` tells whether it hit a yarn
  auto shade = [&](const Vec3& dir, Rng& rng, bool& hit_yarn) -> Col {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh;
    rh.ray.org_x = static_cast<float>(cam.eye.x());
    rh.ray.org_y = static_cast<float>(cam.eye.y());
    rh.ray.org_z = static_cast<float>(cam.eye.z());
    rh.ray.dir_x = static_cast<float>(dir.x());
    rh.ray.dir_y = static_cast<float>(dir.y());
    rh.ray.dir_z = static_cast<float>(dir.z());
    rh.ray.tnear = 0;
    rh.ray.tfar = std::numeric_limits<float>::infinity();
    rh.ray.time = 0;
    rh.ray.mask = ~0u;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(dev.scene, &ctx, &rh);
    hit_yarn = false;
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
      // soft studio gradient
      const float t = static_cast<float>(0.5 * (dir.dot(cam.up) / cam.tan_half_y + 1));
      return hex_colour(0x5E666E) * (1 - t) + hex_colour(0x9AA3AB) * t;
    }
    const Vec3 pos = cam.eye + static_cast<double>(rh.ray.tfar) * dir;
    Vec3 n(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
    n.normalize();
    if (n.dot(dir) > 0) n = -n;
    Col albedo = rh.hit.geomID == OBJECTS_ID ? object_colour : backdrop_colour;
    Vec3 tangent = Vec3::Zero();
    if (rh.hit.geomID == CAPS_ID) {
      hit_yarn = true;
      const int seg = cap_seg[rh.hit.primID];
      albedo = seg_colour[seg];
      tangent = seg_tangent(seg, rh.hit.primID % 2 == 0 ? 0.0 : 1.0);
    } else if (rh.hit.geomID == CURVES_ID) {
      hit_yarn = true;
      const unsigned seg = rh.hit.primID;
      albedo = seg_colour[seg];
      tangent = seg_tangent(static_cast<int>(seg), rh.hit.u);
      // three plies twisting around the yarn: darker grooves between them, faded out when
      // the yarn is too thin on screen to show them without aliasing
      const SegFrame& fr = seg_frame[seg];
      const double r = state.yarn_radius[seg_yarn[seg]];
      const double diameter_px = r * opt.height / (rh.ray.tfar * cam.tan_half_y);
      const double fade = std::clamp((diameter_px - 6) / 10, 0.0, 1.0);
      if (fade > 0) {
        Vec3 ref = fr.ref - fr.ref.dot(tangent) * tangent;
        if (ref.norm() > 1e-9) {
          ref.normalize();
          const double theta = std::atan2(n.dot(tangent.cross(ref)), n.dot(ref));
          const double s = fr.s0 + rh.hit.u * fr.length;
          // each ply turns once per 7.5 r of yarn (a twist angle of about 40°)
          const double v = 0.5 + 0.5 * std::cos(3 * (theta + 2 * PI * s / (7.5 * r)));
          albedo *= static_cast<float>(1 - 0.4 * fade * (1 - v) * (1 - v));
        }
      }
    }
    const Vec3 org = pos + n * eps * 4;
    // soft shadow from the area light
    float direct = 0;
    const double ndotl = n.dot(light);
    if (ndotl > 0) {
      int lit = 0;
      const int rays = std::max(opt.shadow_rays, 1);
      for (int s = 0; s < rays; ++s) {
        double u, v;
        do {
          u = 2 * rng.uniform() - 1;
          v = 2 * rng.uniform() - 1;
        } while (u * u + v * v > 1);
        const Vec3 d = (light + light_spread * (u * light_a + v * light_b)).normalized();
        if (opt.shadow_rays == 0 || !occluded(org, d, std::numeric_limits<float>::infinity()))
          ++lit;
      }
      direct = static_cast<float>(ndotl) * lit / rays;
    }
    // ambient occlusion: cosine-weighted hemisphere rays of limited length
    float ambient = 1;
    if (opt.ao_rays > 0) {
      Vec3 a, b;
      orthonormal_basis(n, a, b);
      int open = 0;
      for (int s = 0; s < opt.ao_rays; ++s) {
        const double r1 = rng.uniform(), r2 = rng.uniform();
        const double rad = std::sqrt(r1), phi = 2 * PI * r2;
        const Vec3 d = (rad * std::cos(phi) * a + rad * std::sin(phi) * b + std::sqrt(1 - r1) * n);
        if (!occluded(org, d, ao_distance)) ++open;
      }
      ambient = static_cast<float>(open) / opt.ao_rays;
    }
    Col c = albedo * (sun * direct + sky * (0.25f + 0.75f * ambient));
    if (hit_yarn && direct > 0) {
      // Kajiya–Kay sheen along the fibres
      const Vec3 h = (light - dir).normalized();
      const double th = tangent.dot(h);
      const double sheen = std::pow(std::max(0.0, 1 - th * th), 30.0);
      c += Col::Constant(static_cast<float>(0.10 * sheen) * direct / static_cast<float>(ndotl));
    }
    return c;
  };

  Image image(opt.width, opt.height);
  image.coverage.assign(static_cast<size_t>(opt.width) * opt.height, 0.0f);
  const int tile = 16;
  const int tiles_x = (opt.width + tile - 1) / tile, tiles_y = (opt.height + tile - 1) / tile;
  const int grid =
      std::max(1, static_cast<int>(std::floor(std::sqrt(static_cast<double>(opt.spp)))));
  tbb::parallel_for(tbb::blocked_range<int>(0, tiles_x * tiles_y),
                    [&](const tbb::blocked_range<int>& range) {
                      for (int t = range.begin(); t != range.end(); ++t) {
                        const int x0 = (t % tiles_x) * tile, y0 = (t / tiles_x) * tile;
                        for (int y = y0; y < std::min(y0 + tile, opt.height); ++y)
                          for (int x = x0; x < std::min(x0 + tile, opt.width); ++x) {
                            Rng rng(static_cast<uint64_t>(y) * opt.width + x);
                            Col sum = Col::Zero();
                            int hits = 0;
                            for (int s = 0; s < opt.spp; ++s) {
                              // stratified on a grid×grid lattice, the rest uniformly jittered
                              double jx, jy;
                              if (s < grid * grid) {
                                jx = ((s % grid) + rng.uniform()) / grid;
                                jy = ((s / grid) + rng.uniform()) / grid;
                              } else {
                                jx = rng.uniform();
                                jy = rng.uniform();
                              }
                              bool hit = false;
                              sum += shade(cam.direction(x + jx, y + jy), rng, hit);
                              hits += hit;
                            }
                            const Col c = sum / static_cast<float>(opt.spp);
                            // gentle highlight compression, then sRGB
                            Col out;
                            for (int k = 0; k < 3; ++k) {
                              const float e = 1.25f * c[k], white = 2.0f;  // extended Reinhard
                              const float v = e * (1 + e / (white * white)) / (1 + e);
                              out[k] = linear_to_srgb(v);
                            }
                            image.set_pixel(x, y, out);
                            image.coverage[static_cast<size_t>(y) * opt.width + x] =
                                static_cast<float>(hits) / opt.spp;
                          }
                      }
                    });
  annotate(image, opt, cam, frame.center());
  return image;
}

}  // namespace knit
