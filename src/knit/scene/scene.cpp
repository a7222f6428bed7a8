#include "knit/scene/scene.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <filesystem>

#include "knit/io/import.hpp"
#include "knit/io/state_file.hpp"
#include "knit/scene/scene_objects.hpp"
#include "knit/spline/fit.hpp"

namespace knit {

namespace {
// segments one yarn described in a scene may have, and all of them together (the paper's
// longest scarf has 64k; a relaxed knit placed with "knits" is not counted)
constexpr int MAX_YARN_SEGMENTS = 200'000;
constexpr int MAX_SCENE_YARN_SEGMENTS = 1'000'000;
}  // namespace

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
  for (size_t k = 0; k < r.size(); ++k) p.col(k) = r.at(k).coordinates(MAX_SCENE_COORDINATE);
  return p;
}

// a length (cm): > 0 and at most MAX_SCENE_COORDINATE
double scene_length(const JsonReader& r) {
  const double x = r.positive();
  if (!(x <= MAX_SCENE_COORDINATE))
    r.fail("expected at most " + short_number(MAX_SCENE_COORDINATE) + " cm, got " +
           short_number(x));
  return x;
}

// a yarn's segments each have a length: four coinciding control points make none (named
// here with the yarn's field path, rather than later by the segment's global index)
void check_segments(const JsonReader& y, const Eigen::Matrix3Xd& cp) {
  for (Eigen::Index i = 0; i + 3 < cp.cols(); ++i) {
    double spread = 0;
    for (int a = 1; a < 4; ++a)
      spread = std::max(spread, (cp.col(i + a) - cp.col(i)).cwiseAbs().maxCoeff());
    if (!(spread > 0))
      y.fail("segment " + std::to_string(i) + " has zero length: its 4 control points (" +
             std::to_string(i) + " to " + std::to_string(i + 3) + ") coincide");
  }
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
    return fit_polyline(poly, y.at("segments").integer(1, MAX_YARN_SEGMENTS));
  }
  if (y.has("line")) {
    const JsonReader l = y.at("line");
    l.allow_keys({"from", "to", "segments"});
    const Eigen::Vector3d a = l.at("from").coordinates(MAX_SCENE_COORDINATE),
                          b = l.at("to").coordinates(MAX_SCENE_COORDINATE);
    if ((b - a).norm() <= 0) l.fail("\"from\" and \"to\" must differ");
    return line_points(a, b, l.at("segments").integer(1, MAX_YARN_SEGMENTS));
  }
  if (y.has("helix")) {
    const JsonReader h = y.at("helix");
    h.allow_keys({"center", "radius", "pitch", "turns", "segments"});
    const Eigen::Vector3d c = h.has("center") ? h.at("center").coordinates(MAX_SCENE_COORDINATE)
                                              : Eigen::Vector3d::Zero();
    const double radius = scene_length(h.at("radius"));
    const double pitch =
        h.at("pitch").number_in(-MAX_SCENE_COORDINATE, MAX_SCENE_COORDINATE, "cm per turn");
    const double turns = h.at("turns").positive();
    if (!(turns <= 1e6))
      h.at("turns").fail("expected at most 1e+06 turns, got " + short_number(turns));
    const int segs = h.at("segments").integer(1, MAX_YARN_SEGMENTS);
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
  const Eigen::Vector3d centre =
      c.has("center") ? c.at("center").coordinates(MAX_SCENE_COORDINATE) : Eigen::Vector3d::Zero();
  const double radius = scene_length(c.at("radius"));
  const double degrees = c.has("degrees") ? c.at("degrees").positive() : 330.0;
  if (degrees > 360)
    c.at("degrees").fail("expected at most 360 degrees, got " + short_number(degrees));
  const int segs = c.at("segments").integer(1, MAX_YARN_SEGMENTS);
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
  if (t < 0 || t > 1) r.at("t").fail("expected t in [0, 1], got " + short_number(t));
  return {nseg + seg, t};
}

// a relaxed knit from a .kstate, placed by "translate" and "rotate" (about the origin,
// rotation first); it starts at rest
struct PlacedKnit {
  Eigen::Matrix3Xd points;
  std::vector<StitchCoord> stitch;
  std::vector<Glue> glues;  // local segment indices
  bool in_the_round = false;
  std::string source;
};

PlacedKnit parse_knit(const JsonReader& k, const std::string& scene_path) {
  k.allow_keys({"state", "translate", "rotate"});
  const std::string path = k.at("state").string();
  const std::filesystem::path base = std::filesystem::path(scene_path).parent_path();
  const std::filesystem::path full =
      std::filesystem::path(path).is_absolute() ? std::filesystem::path(path) : base / path;
  StateFile f;
  try {
    f = read_state_file(full.string());
  } catch (const std::exception& e) {
    k.at("state").fail(e.what());
  }
  if (f.yarn_cp_counts.size() != 1)
    k.at("state").fail(full.string() + " holds " + std::to_string(f.yarn_cp_counts.size()) +
                       " yarns; a knit is one yarn");
  if (f.stitch.empty())
    k.at("state").fail(full.string() +
                       " has no stitch coordinates: write it with `knitsim relax PATTERN`");
  const Eigen::Vector3d t = k.has("translate") ? k.at("translate").coordinates(MAX_SCENE_COORDINATE)
                                               : Eigen::Vector3d::Zero();
  const Eigen::Quaterniond rot =
      k.has("rotate") ? parse_rotation(k.at("rotate")) : Eigen::Quaterniond::Identity();
  PlacedKnit out;
  out.source = full.string();
  out.points =
      (rot.toRotationMatrix() * Eigen::Map<const Eigen::Matrix3Xd>(f.state.q.data(), 3, f.num_cp()))
          .colwise() +
      t;
  out.stitch = f.stitch;
  out.in_the_round = f.knit && f.knit->in_the_round;
  for (Glue g : f.glues) {
    // the glues hold the ends where they are (closed, for a knit relaxed past its glue
    // closing time): the gap stays the placed yarn's own, so the knit starts on its
    // constraints
    auto at = [&](const YarnPoint& p) -> Eigen::Vector3d {
      return out.points.middleCols<4>(p.segment) * bspline_basis(p.t);
    };
    g.gap = at(g.a) - at(g.b);
    g.close_time = std::numeric_limits<double>::infinity();
    out.glues.push_back(g);
  }
  return out;
}

// an inclusive range [first, last] of stitch rows or columns (negative counts from the
// end: -1 is the last), checked against the knit's extent
std::pair<int, int> parse_stitch_range(const JsonReader& range, bool rows,
                                       const std::vector<StitchCoord>& stitch) {
  range.require_array(2);
  if (range.size() != 2)
    range.fail("expected [first, last], got " + std::to_string(range.size()) + " elements");
  int lo = range.at(0).integer(-1000000), hi = range.at(1).integer(-1000000);
  const std::string given = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  int extent = 0;
  for (const StitchCoord& s : stitch) extent = std::max(extent, (rows ? s.row : s.col) + 1);
  if (lo < 0) lo += extent;
  if (hi < 0) hi += extent;
  if (lo < 0 || hi >= extent || lo > hi)
    range.fail("expected " + std::string(rows ? "rows" : "columns") + " within [0, " +
               std::to_string(extent - 1) + "] (negative counts from the end), first ≤ last, got " +
               given);
  return {lo, hi};
}

// what a clamp holds: "rows" and/or "cols" of a knit's stitches (both: the stitches in
// both ranges, e.g. a corner) hold the control points of every segment in them;
// "points" lists yarn points
void parse_clamp_points(const JsonReader& c, const ModelBuilder& b,
                        const std::vector<StitchCoord>& stitch, const std::vector<SceneKnit>& knits,
                        Clamp& clamp) {
  const bool by_stitch = c.has("rows") || c.has("cols");
  if (by_stitch == c.has("points"))
    c.fail("expected \"rows\" and/or \"cols\" of a knit's stitches, or \"points\"");
  if (c.has("points")) {
    const JsonReader list = c.at("points");
    list.require_array(1);
    for (size_t k = 0; k < list.size(); ++k) {
      const JsonReader p = list.at(k);
      p.allow_keys({"yarn", "segment", "t", "at"});
      clamp.points.push_back(parse_point(p, b, true));
    }
    return;
  }
  if (knits.empty())
    c.at(c.has("rows") ? "rows" : "cols")
        .fail("the scene has no knit to clamp by stitch coordinates");
  std::pair<int, int> rows{-1000000000, 1000000000}, cols = rows;
  if (c.has("rows")) rows = parse_stitch_range(c.at("rows"), true, stitch);
  if (c.has("cols")) cols = parse_stitch_range(c.at("cols"), false, stitch);
  // the control points of the segments in range, each once: segment i of a yarn whose
  // first segment is s0 and first control point c0 uses c0 + (i − s0) … + 3
  std::vector<int> cps;
  int seg0 = 0, cp0 = 0;
  for (int y = 0; y < b.num_yarns(); ++y) {
    const int nseg = (y + 1 < b.num_yarns() ? b.segment_index(y + 1, 0) : b.num_segments()) - seg0;
    for (int i = seg0; i < seg0 + nseg; ++i)
      if (stitch[i].row >= rows.first && stitch[i].row <= rows.second &&
          stitch[i].col >= cols.first && stitch[i].col <= cols.second && stitch[i].row >= 0)
        for (int a = 0; a < 4; ++a) cps.push_back(cp0 + (i - seg0) + a);
    seg0 += nseg;
    cp0 += nseg + 3;
  }
  if (cps.empty()) c.fail("no stitch lies in both the rows and the columns given");
  std::sort(cps.begin(), cps.end());
  cps.erase(std::unique(cps.begin(), cps.end()), cps.end());
  clamp.control_points = std::move(cps);
}

}  // namespace

Eigen::Quaterniond parse_rotation(const JsonReader& r) {
  r.allow_keys({"axis", "degrees"});
  const Eigen::Vector3d axis = r.at("axis").vec3();
  if (!(axis.norm() > 0)) r.at("axis").fail("the rotation axis must not be zero");
  const double degrees = r.at("degrees").number();
  if (!(std::abs(degrees) <= 1e6))
    r.at("degrees").fail("expected at most 1e+06 degrees either way, got " + short_number(degrees));
  return Eigen::Quaterniond(Eigen::AngleAxisd(degrees * M_PI / 180, axis.normalized()));
}

std::vector<Keyframe> parse_keyframes(const JsonReader& r) {
  r.require_array(1);
  std::vector<Keyframe> frames;
  for (size_t k = 0; k < r.size(); ++k) {
    const JsonReader f = r.at(k);
    f.allow_keys({"time", "translate", "rotate"});
    Keyframe kf;
    kf.time = f.at("time").positive(true);
    if (!(kf.time <= MAX_DURATION))
      f.at("time").fail("expected a time of at most " + short_number(MAX_DURATION) + " s, got " +
                        short_number(kf.time));
    if (k > 0 && !(kf.time > frames.back().time))
      f.at("time").fail("keyframe times must increase (got " + short_number(kf.time) + " s after " +
                        short_number(frames.back().time) + " s)");
    if (f.has("translate")) kf.translation = f.at("translate").coordinates(MAX_SCENE_COORDINATE);
    if (f.has("rotate")) kf.rotation = parse_rotation(f.at("rotate"));
    frames.push_back(kf);
  }
  return frames;
}

namespace {

// parse_scene with the file named in every message
Scene parse_scene_file(const nlohmann::json& doc, const std::string& path) {
  try {
    return parse_scene(doc, path);
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(path + ": " + e.what());
  }
}

}  // namespace

Params parse_params(const JsonReader& r, Params p) {
  // the keys are the parameter table's (model/params.def) and "preset"
  std::vector<std::string> keys = {"preset"};
  for (const ParamDecl& d : param_table()) keys.push_back(d.name);
  r.allow_keys(keys);
  if (r.has("preset")) {
    const std::string preset = r.at("preset").string();
    if (preset == "simulation")
      p = Params::simulation();
    else if (preset == "relaxation")
      p = Params::relaxation();
    else
      r.at("preset").fail("expected \"simulation\" or \"relaxation\", got \"" + preset + "\"");
  }
  for (const ParamDecl& d : param_table()) {
    if (!r.has(d.name)) continue;
    const JsonReader v = r.at(d.name);
    switch (d.type) {
      case ParamType::BOOLEAN:
        d.set(p, v.boolean() ? 1 : 0);
        continue;
      case ParamType::CHOICE: {
        const std::string name = v.string();
        const std::vector<std::string>& names = d.choices();
        const auto it = std::find(names.begin(), names.end(), name);
        if (it == names.end()) {
          std::string expected;
          for (size_t k = 0; k < names.size(); ++k)
            expected += (k == 0                  ? ""
                         : k + 1 == names.size() ? " or "
                                                 : ", ") +
                        ("\"" + names[k] + "\"");
          v.fail("expected " + expected + ", got \"" + name + "\"");
        }
        d.set(p, static_cast<double>(it - names.begin()));
        continue;
      }
      case ParamType::INTEGER:
        d.set(p, v.integer(static_cast<int>(d.min)));
        break;
      case ParamType::REAL:
        d.set(p, d.min > 0 ? v.positive() : d.min == 0 ? v.positive(true) : v.number());
        break;
    }
    // every number within its working range, named by its key
    try {
      check_param(d.name, d.get(p));
    } catch (const std::invalid_argument& e) {
      v.fail(e.what());
    }
  }
  if (r.has("quadrature_points") && p.discretisation.quadrature_points % 2 == 0)
    r.at("quadrature_points")
        .fail("Simpson's rule needs an odd number of points, got " +
              std::to_string(p.discretisation.quadrature_points));
  return p;
}

Scene parse_scene(const nlohmann::json& doc, const std::string& source, const Params& base) {
  const JsonReader root(doc, source);
  root.allow_keys({"params", "gravity", "time_step", "duration", "output_every", "yarns", "knits",
                   "pins", "glue", "clamps", "objects", "description"});
  Params params = root.has("params") ? parse_params(root.at("params"), base) : base;
  if (root.has("gravity")) params.gravity = root.at("gravity").vec3();
  Scene scene;
  if (root.has("time_step")) {
    if (root.has("params") && root.at("params").has("time_step"))
      root.at("time_step").fail("the time step is given twice (also in \"params\")");
    params.solver.time_step = root.at("time_step").positive();
    try {
      check_param("time_step", params.solver.time_step);
    } catch (const std::invalid_argument& e) {
      root.at("time_step").fail(e.what());
    }
  }
  if (root.has("gravity")) {
    try {
      validate_params(params);
    } catch (const std::invalid_argument& e) {
      root.at("gravity").fail(e.what());
    }
  }
  if (root.has("duration")) {
    scene.duration = root.at("duration").positive();
    try {
      check_duration(scene.duration, params.solver.time_step);
    } catch (const std::invalid_argument& e) {
      root.at("duration").fail(e.what());
    }
  }
  if (root.has("output_every")) scene.output_every = root.at("output_every").integer(1);
  if (root.has("description")) root.at("description").string();
  if (!root.has("knits")) root.at("yarns");  // a scene without knits needs yarns

  ModelBuilder builder;
  std::vector<StitchCoord> stitch;
  std::vector<Glue> knit_glues;
  if (root.has("yarns")) {
    const JsonReader yarns = root.at("yarns");
    yarns.require_array(root.has("knits") ? 0 : 1);
    for (size_t k = 0; k < yarns.size(); ++k) {
      const JsonReader y = yarns.at(k);
      if (y.has("import")) {
        y.allow_keys({"import"});
        for (const Eigen::Matrix3Xd& cp : parse_import(y, source)) builder.add_yarn(cp);
      } else {
        const Eigen::Matrix3Xd cp = parse_yarn(y);
        check_segments(y, cp);
        builder.add_yarn(cp);
      }
      if (builder.num_segments() > MAX_SCENE_YARN_SEGMENTS)
        y.fail("the scene's yarns have " + std::to_string(builder.num_segments()) +
               " segments so far, more than a scene may have (" +
               std::to_string(MAX_SCENE_YARN_SEGMENTS) + ")");
    }
  }
  stitch.assign(builder.num_segments(), StitchCoord{});
  if (root.has("knits")) {
    const JsonReader knits = root.at("knits");
    knits.require_array(1);
    // the non-rigid damping regions are built from stitch coordinates, which two knits
    // would share
    if (knits.size() > 1) knits.fail("a scene holds at most one knit for now");
    for (size_t k = 0; k < knits.size(); ++k) {
      const PlacedKnit knit = parse_knit(knits.at(k), source);
      const int seg0 = builder.num_segments();
      const int yarn = builder.add_yarn(knit.points);
      stitch.insert(stitch.end(), knit.stitch.begin(), knit.stitch.end());
      for (Glue g : knit.glues) {
        g.a.segment += seg0;
        g.b.segment += seg0;
        knit_glues.push_back(g);
      }
      scene.knits.push_back({knit.source, yarn, knit.in_the_round});
    }
  }
  builder.set_stitches(stitch);
  for (const Glue& g : knit_glues) builder.add_glue(g);

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
      if (pr.has("velocity"))
        pin.velocity = pr.at("velocity").coordinates(MAX_SCENE_COORDINATE, "cm/s");
      if (pr.has("start")) pin.start = pr.at("start").positive(true);
      if (pr.has("stop")) {
        pin.stop = pr.at("stop").positive(true);
        if (pin.stop < pin.start)
          pr.at("stop").fail("\"stop\" must not be before \"start\" (got " +
                             short_number(pin.stop) + " s, before " + short_number(pin.start) +
                             " s)");
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
  if (root.has("clamps")) {
    const JsonReader clamps = root.at("clamps");
    clamps.require_array();
    std::vector<std::string> names;
    for (size_t k = 0; k < clamps.size(); ++k) {
      const JsonReader cr = clamps.at(k);
      cr.allow_keys({"name", "rows", "cols", "points", "keyframes"});
      Clamp clamp;
      clamp.name = cr.has("name") ? cr.at("name").string() : "clamp" + std::to_string(k);
      if (clamp.name.empty() || clamp.name.find_first_of(",\"\n") != std::string::npos)
        cr.at("name").fail("a clamp's name must be non-empty, without commas or quotes");
      if (std::find(names.begin(), names.end(), clamp.name) != names.end())
        cr.at("name").fail("two clamps are called \"" + clamp.name + "\"");
      names.push_back(clamp.name);
      parse_clamp_points(cr, builder, stitch, scene.knits, clamp);
      if (cr.has("keyframes")) clamp.keyframes = parse_keyframes(cr.at("keyframes"));
      builder.add_clamp(clamp);
    }
  }
  // the non-rigid damping filter acts on a placed knit's stitches: without one, its
  // parameters would be read and ignored
  if (scene.knits.empty() && root.has("params"))
    for (const char* key : {"alpha_small", "alpha_large"})
      if (root.at("params").has(key))
        root.at("params").at(key).fail(
            "the non-rigid damping acts on a placed knit's stitches, and this scene has no "
            "\"knits\"");
  scene.model = builder.build(params);
  if (root.has("objects")) scene.model.objects = parse_objects(root.at("objects"), source);
  scene.state.q = q0;
  scene.state.v = Eigen::VectorXd::Zero(q0.size());
  scene.state.time = 0;
  return scene;
}

Scene scene_from_knit_state(const std::string& kstate_path, const Params& params) {
  const std::string full = std::filesystem::absolute(kstate_path).string();
  nlohmann::json doc = {{"knits", nlohmann::json::array({{{"state", full}}})}};
  Scene scene = parse_scene(doc, full, params);
  return scene;
}

Scene load_scene_with_knit(const std::string& path, const std::string& kstate_path) {
  nlohmann::json doc = parse_json_file(path);
  if (!doc.is_object() || !doc.contains("knits") || !doc["knits"].is_array() ||
      doc["knits"].size() != 1 || !doc["knits"][0].is_object())
    throw InputError(path +
                     ": knits: a knit given on the command line replaces the scene's one "
                     "knit, and this scene has none or several");
  doc["knits"][0]["state"] = std::filesystem::absolute(kstate_path).string();
  return parse_scene_file(doc, path);
}

Scene load_scene(const std::string& path) {
  return parse_scene_file(parse_json_file(path), path);
}

}  // namespace knit
