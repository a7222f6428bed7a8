#include "knit/scene/scene.hpp"

#include <cmath>

#include <filesystem>

#include "knit/io/import.hpp"
#include "knit/spline/fit.hpp"

namespace knit {

namespace {

// control points of a straight yarn from `a` to `b` (the curve starts at a and ends at b)
Eigen::Matrix3Xd line_points(const Eigen::Vector3d& a, const Eigen::Vector3d& b, int segments) {
  Eigen::Matrix3Xd cp(3, segments + 3);
  const Eigen::Vector3d d = (b - a) / segments;
  for (int k = 0; k < segments + 3; ++k) cp.col(k) = a + (k - 1) * d;
  return cp;
}

Eigen::Matrix3Xd read_points(const JsonReader& r, size_t min_size) {
  r.require_array(min_size);
  Eigen::Matrix3Xd p(3, r.size());
  for (size_t k = 0; k < r.size(); ++k) p.col(k) = r.at(k).vec3();
  return p;
}

// yarns read from a .yarns/.bcc/.obj file, path relative to the scene file
std::vector<Eigen::Matrix3Xd> parse_import(const JsonReader& y, const std::string& scene_path) {
  const JsonReader imp = y.at("import");
  ImportOptions opt;
  std::string path;
  if (imp.value().is_string()) {
    path = imp.string();
  } else {
    imp.allow_keys({"path", "scale", "segments_per_cm"});
    path = imp.at("path").string();
    if (imp.has("scale")) opt.scale = imp.at("scale").positive();
    if (imp.has("segments_per_cm")) opt.segments_per_cm = imp.at("segments_per_cm").positive();
  }
  const std::filesystem::path base = std::filesystem::path(scene_path).parent_path();
  const std::filesystem::path full =
      std::filesystem::path(path).is_absolute() ? std::filesystem::path(path) : base / path;
  std::vector<Eigen::Matrix3Xd> out;
  try {
    for (const ImportedYarn& yarn : import_yarns(full.string(), opt))
      out.push_back(yarn.control_points);
  } catch (const std::exception& e) {
    imp.fail(e.what());
  }
  return out;
}

Eigen::Matrix3Xd parse_yarn(const JsonReader& y) {
  y.allow_keys({"points", "polyline", "segments", "line", "helix", "circle", "import"});
  int kinds =
      y.has("points") + y.has("polyline") + y.has("line") + y.has("helix") + y.has("circle");
  if (kinds != 1)
    y.fail(
        "expected exactly one of \"points\", \"polyline\", \"line\", \"helix\", \"circle\", "
        "\"import\"");
  if (y.has("segments") && !y.has("polyline"))
    y.at("segments").fail("\"segments\" belongs to a \"polyline\" yarn");
  if (y.has("points")) {
    const JsonReader p = y.at("points");
    p.require_array();
    if (p.size() < 4)
      p.fail("a cubic B-spline yarn needs at least 4 control points, got " +
             std::to_string(p.size()));
    return read_points(p, 4);
  }
  if (y.has("polyline")) {
    const Eigen::Matrix3Xd poly = read_points(y.at("polyline"), 2);
    if (!(polyline_length(poly) > 0)) y.at("polyline").fail("polyline has zero length");
    return fit_polyline(poly, y.at("segments").integer(1));
  }
  if (y.has("line")) {
    const JsonReader l = y.at("line");
    l.allow_keys({"from", "to", "segments"});
    const Eigen::Vector3d a = l.at("from").vec3(), b = l.at("to").vec3();
    if ((b - a).norm() <= 0) l.fail("\"from\" and \"to\" must differ");
    return line_points(a, b, l.at("segments").integer(1));
  }
  if (y.has("helix")) {
    const JsonReader h = y.at("helix");
    h.allow_keys({"center", "radius", "pitch", "turns", "segments"});
    const Eigen::Vector3d c = h.has("center") ? h.at("center").vec3() : Eigen::Vector3d::Zero();
    const double radius = h.at("radius").positive();
    const double pitch = h.at("pitch").number();
    const double turns = h.at("turns").positive();
    const int segs = h.at("segments").integer(1);
    const int n = 16 * segs + 1;
    Eigen::Matrix3Xd poly(3, n);
    for (int k = 0; k < n; ++k) {
      const double s = turns * static_cast<double>(k) / (n - 1);
      poly.col(k) = c + Eigen::Vector3d(radius * std::cos(2 * M_PI * s),
                                        radius * std::sin(2 * M_PI * s), pitch * s);
    }
    return fit_polyline(poly, segs);
  }
  const JsonReader c = y.at("circle");
  c.allow_keys({"center", "radius", "degrees", "segments"});
  const Eigen::Vector3d centre = c.has("center") ? c.at("center").vec3() : Eigen::Vector3d::Zero();
  const double radius = c.at("radius").positive();
  const double degrees = c.has("degrees") ? c.at("degrees").positive() : 330.0;
  if (degrees > 360) c.at("degrees").fail("expected at most 360 degrees");
  const int segs = c.at("segments").integer(1);
  const int n = 16 * segs + 1;
  Eigen::Matrix3Xd poly(3, n);
  for (int k = 0; k < n; ++k) {
    const double a = degrees * M_PI / 180 * static_cast<double>(k) / (n - 1);
    poly.col(k) = centre + radius * Eigen::Vector3d(std::cos(a), std::sin(a), 0);
  }
  return fit_polyline(poly, segs);
}

YarnPoint parse_point(const JsonReader& r, const ModelBuilder& b, bool allow_at) {
  const int yarn = r.at("yarn").integer(0);
  if (yarn >= b.num_yarns())
    r.at("yarn").fail("yarn " + std::to_string(yarn) + " does not exist (the scene has " +
                      std::to_string(b.num_yarns()) + " yarns)");
  const int nseg = b.segment_index(yarn, 0);  // validates yarn, gives base
  auto local_count = [&]() {
    return (yarn + 1 < b.num_yarns() ? b.segment_index(yarn + 1, 0) : b.num_segments()) - nseg;
  };
  YarnPoint p;
  if (allow_at && r.has("at")) {
    if (r.has("segment") || r.has("t")) r.fail("give either \"at\" or \"segment\"/\"t\", not both");
    const std::string at = r.at("at").string();
    if (at == "start") {
      p = {nseg, 0.0};
    } else if (at == "end") {
      p = {nseg + local_count() - 1, 1.0};
    } else {
      r.at("at").fail("expected \"start\" or \"end\", got \"" + at + "\"");
    }
    return p;
  }
  const int seg = r.at("segment").integer(0);
  if (seg >= local_count())
    r.at("segment").fail("segment " + std::to_string(seg) + " does not exist on yarn " +
                         std::to_string(yarn) + " (it has " + std::to_string(local_count()) +
                         " segments)");
  const double t = r.has("t") ? r.at("t").number() : 0.0;
  if (t < 0 || t > 1) r.at("t").fail("expected t in [0, 1]");
  return {nseg + seg, t};
}

}  // namespace

Params parse_params(const JsonReader& r, Params p) {
  r.allow_keys({"preset", "radius", "density", "k_len", "k_bend", "k_global", "k_contact", "k_dt",
                "k_dn", "alpha_small", "alpha_large", "quadrature_points", "contact_points",
                "length_constraints", "contact", "constraint_tolerance",
                "max_projection_iterations"});
  if (r.has("preset")) {
    const std::string preset = r.at("preset").string();
    if (preset == "simulation")
      p = Params::simulation();
    else if (preset == "relaxation")
      p = Params::relaxation();
    else
      r.at("preset").fail("expected \"simulation\" or \"relaxation\", got \"" + preset + "\"");
  }
  if (r.has("radius")) p.radius = r.at("radius").positive();
  if (r.has("density")) p.density = r.at("density").positive();
  if (r.has("k_len")) p.k_len = r.at("k_len").positive(true);
  if (r.has("k_bend")) p.k_bend = r.at("k_bend").positive(true);
  if (r.has("k_global")) p.k_global = r.at("k_global").positive(true);
  if (r.has("k_contact")) p.k_contact = r.at("k_contact").positive(true);
  if (r.has("k_dt")) p.k_dt = r.at("k_dt").positive(true);
  if (r.has("k_dn")) p.k_dn = r.at("k_dn").positive(true);
  for (auto [key, dst] :
       {std::pair{"alpha_small", &p.alpha_small}, {"alpha_large", &p.alpha_large}}) {
    if (!r.has(key)) continue;
    *dst = r.at(key).positive(true);
    if (*dst > 1) r.at(key).fail("expected a value in [0, 1]");
  }
  if (r.has("quadrature_points")) {
    p.quadrature_points = r.at("quadrature_points").integer(3);
    if (p.quadrature_points % 2 == 0)
      r.at("quadrature_points").fail("Simpson's rule needs an odd number of points");
  }
  if (r.has("contact_points")) p.contact_points = r.at("contact_points").integer(1);
  if (r.has("length_constraints")) p.length_constraints = r.at("length_constraints").boolean();
  if (r.has("contact")) p.contact = r.at("contact").boolean();
  if (r.has("constraint_tolerance"))
    p.constraint_tolerance = r.at("constraint_tolerance").positive();
  if (r.has("max_projection_iterations"))
    p.max_projection_iterations = r.at("max_projection_iterations").integer(1);
  return p;
}

Scene parse_scene(const nlohmann::json& doc, const std::string& source) {
  const JsonReader root(doc, source);
  root.allow_keys({"params", "gravity", "time_step", "duration", "output_every", "yarns", "pins",
                   "glue", "description"});
  Params params = root.has("params") ? parse_params(root.at("params"), Params::simulation())
                                     : Params::simulation();
  if (root.has("gravity")) params.gravity = root.at("gravity").vec3();
  Scene scene;
  if (root.has("time_step")) scene.time_step = root.at("time_step").positive();
  if (root.has("duration")) scene.duration = root.at("duration").positive(true);
  if (root.has("output_every")) scene.output_every = root.at("output_every").integer(1);
  if (root.has("description")) root.at("description").string();

  ModelBuilder builder;
  const JsonReader yarns = root.at("yarns");
  yarns.require_array(1);
  for (size_t k = 0; k < yarns.size(); ++k) {
    const JsonReader y = yarns.at(k);
    if (y.has("import")) {
      y.allow_keys({"import"});
      for (const Eigen::Matrix3Xd& cp : parse_import(y, source)) builder.add_yarn(cp);
    } else {
      builder.add_yarn(parse_yarn(y));
    }
  }

  const Eigen::VectorXd q0 = builder.positions();
  // pins start where their yarn point is; build a throwaway model for positions
  const Model shape = builder.build(params);
  if (root.has("pins")) {
    const JsonReader pins = root.at("pins");
    pins.require_array();
    for (size_t k = 0; k < pins.size(); ++k) {
      const JsonReader pr = pins.at(k);
      pr.allow_keys({"yarn", "at", "segment", "t", "velocity", "start", "stop"});
      Pin pin;
      pin.at = parse_point(pr, builder, true);
      pin.origin = point_position(shape, q0, pin.at);
      if (pr.has("velocity")) pin.velocity = pr.at("velocity").vec3();
      if (pr.has("start")) pin.start = pr.at("start").positive(true);
      if (pr.has("stop")) {
        pin.stop = pr.at("stop").positive(true);
        if (pin.stop < pin.start) pr.at("stop").fail("\"stop\" must not be before \"start\"");
      }
      builder.add_pin(pin);
    }
  }
  if (root.has("glue")) {
    const JsonReader glue = root.at("glue");
    glue.require_array();
    for (size_t k = 0; k < glue.size(); ++k) {
      const JsonReader gr = glue.at(k);
      gr.allow_keys({"a", "b"});
      const JsonReader a = gr.at("a"), b = gr.at("b");
      a.allow_keys({"yarn", "segment", "t"});
      b.allow_keys({"yarn", "segment", "t"});
      builder.add_glue({parse_point(a, builder, false), parse_point(b, builder, false)});
    }
  }
  scene.model = builder.build(params);
  scene.state.q = q0;
  scene.state.v = Eigen::VectorXd::Zero(q0.size());
  scene.state.time = 0;
  return scene;
}

Scene load_scene(const std::string& path) {
  const nlohmann::json doc = parse_json_file(path);
  try {
    return parse_scene(doc, path);
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(path + ": " + e.what());
  }
}

}  // namespace knit
