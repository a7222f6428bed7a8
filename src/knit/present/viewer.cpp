#include "knit/present/viewer.hpp"

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "knit/io/states.hpp"
#include "knit/objects/mesh_shape.hpp"
#include "knit/present/render.hpp"

namespace knit {

namespace {

std::string base64(const unsigned char* data, size_t size) {
  static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((size + 2) / 3 * 4);
  for (size_t i = 0; i < size; i += 3) {
    const unsigned a = data[i], b = i + 1 < size ? data[i + 1] : 0,
                   c = i + 2 < size ? data[i + 2] : 0;
    const unsigned n = (a << 16) | (b << 8) | c;
    out += table[(n >> 18) & 63];
    out += table[(n >> 12) & 63];
    out += i + 1 < size ? table[(n >> 6) & 63] : '=';
    out += i + 2 < size ? table[n & 63] : '=';
  }
  return out;
}

// nothing in a script may end the <script> element early
std::string script_safe(std::string s) {
  for (size_t at = 0; (at = s.find("</script", at)) != std::string::npos; at += 2)
    s.replace(at, 2, "<\\/");
  return s;
}

// nor in the page's JSON data, where the objects' names are the user's: a '<' can only be
// inside one of its strings, where \u003c is the same character
std::string json_safe(const std::string& json) {
  std::string out;
  out.reserve(json.size());
  for (char c : json) out += c == '<' ? std::string("\\u003c") : std::string(1, c);
  return out;
}

std::string read_script(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw std::runtime_error("viewer: " + path.string() +
                             " is missing: install Debian's libjs-three (scripts/setup.sh does)");
  std::stringstream ss;
  ss << in.rdbuf();
  return script_safe(ss.str());
}

template <class T>
std::string base64_of(const std::vector<T>& values) {
  return base64(reinterpret_cast<const unsigned char*>(values.data()), values.size() * sizeof(T));
}

// Grid cells along an object's box diagonal for its surface on the page: a sphere is about 55
// cells across, smooth with the page's vertex normals, and a floor's slab a few thousand
// triangles.
constexpr double OBJECT_CELLS = 96;

// The objects for the page (viewer.js): each one's surface in its own frame at the first
// time, where it lies within `region` (world, cm), and its pose per frame (one when it does
// not move). Objects wholly outside the region are left out. Adds their size to `bytes`.
nlohmann::json page_objects(const std::vector<std::shared_ptr<const SceneObject>>& objects,
                            const std::vector<double>& times, const Eigen::AlignedBox3d& region,
                            long long& bytes) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& object : objects) {
    const ObjectFrame f0(*object, times.front());
    Eigen::AlignedBox3d local;
    for (int c = 0; c < 8; ++c)
      local.extend(f0.rotation().transpose() *
                   (region.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c)) - f0.origin()));
    const Eigen::AlignedBox3d inside = local.intersection(object->shape->bounds());
    if (inside.isEmpty() || !inside.diagonal().allFinite()) continue;
    const TriangleMesh mesh =
        surface_mesh(*object->shape, local, inside.diagonal().norm() / OBJECT_CELLS);
    if (mesh.triangles.empty()) continue;
    std::vector<float> vertices;
    vertices.reserve(3 * mesh.vertices.size());
    for (const Eigen::Vector3d& v : mesh.vertices)
      for (int k = 0; k < 3; ++k) vertices.push_back(static_cast<float>(v[k]));
    std::vector<uint32_t> triangles;
    triangles.reserve(3 * mesh.triangles.size());
    for (const Eigen::Vector3i& t : mesh.triangles)
      for (int k = 0; k < 3; ++k) triangles.push_back(static_cast<uint32_t>(t[k]));
    nlohmann::json poses = nlohmann::json::array();
    for (size_t f = 0; f < (object->moving() ? times.size() : 1); ++f) {
      const ObjectFrame at(*object, times[f]);
      const Eigen::Quaterniond r(at.rotation());
      poses.push_back(
          {at.origin().x(), at.origin().y(), at.origin().z(), r.x(), r.y(), r.z(), r.w()});
    }
    bytes += static_cast<long long>((vertices.size() + triangles.size()) * 4 * 4 / 3 +
                                    poses.size() * 7 * 24);
    out.push_back({{"name", object->name},
                   {"vertices", base64_of(vertices)},
                   {"triangles", base64_of(triangles)},
                   {"poses", poses}});
  }
  return out;
}

std::string html_escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '<')
      out += "&lt;";
    else if (c == '>')
      out += "&gt;";
    else if (c == '&')
      out += "&amp;";
    else if (c == '"')
      out += "&quot;";
    else
      out += c;
  }
  return out;
}

// The page's own script (src/knit/present/viewer.js, built in as a string by CMakeLists.txt)
const char* const VIEWER_JS =
#include "knit/present/viewer_js.inc"
    ;

}  // namespace

std::string viewer_html(const std::vector<StateFile>& frames, const std::vector<double>& times,
                        const ViewerOptions& o) {
  check_state_sequence(frames, times, "viewer");
  if (o.samples_per_segment < 1 || o.samples_per_segment > 64)
    throw std::invalid_argument("viewer: samples per segment must be in [1, 64]");
  if (o.sides < 3 || o.sides > 64) throw std::invalid_argument("viewer: sides must be in [3, 64]");
  const size_t ncp = static_cast<size_t>(frames[0].num_cp());
  long long bytes = static_cast<long long>(frames.size() * ncp * 12 * 4 / 3);
  if (bytes > o.max_bytes)
    throw std::runtime_error("viewer: " + std::to_string(frames.size()) + " frames of " +
                             std::to_string(ncp) + " control points make a page of about " +
                             std::to_string(bytes >> 20) + " MB; show fewer frames (every Nth)");
  // the box the camera frames: every frame's yarn and bounded objects (as render frames a
  // state among objects); the objects are drawn within it grown by half its largest side, as
  // render draws them (a floor is a slab that wide)
  Eigen::AlignedBox3d box;
  for (const StateFile& f : frames) box.extend(scene_bounds(f, o.objects));
  Eigen::AlignedBox3d region = box;
  region.min().array() -= 0.5 * box.sizes().maxCoeff();
  region.max().array() += 0.5 * box.sizes().maxCoeff();
  const nlohmann::json objects = page_objects(o.objects, times, region, bytes);
  if (bytes > o.max_bytes)
    throw std::runtime_error("viewer: the frames and the surfaces of " +
                             std::to_string(o.objects.size()) + " objects make a page of about " +
                             std::to_string(bytes >> 20) + " MB; show fewer frames (every Nth)");
  const std::filesystem::path dir(o.three_dir);
  const std::string three = read_script(dir / "three.min.js");
  const std::string orbit = read_script(dir / "examples/js/controls/OrbitControls.js");

  std::vector<float> q;
  q.reserve(frames.size() * 3 * ncp);
  for (const StateFile& f : frames)
    for (Eigen::Index k = 0; k < f.state.q.size(); ++k)
      q.push_back(static_cast<float>(f.state.q[k]));
  nlohmann::json d;
  d["counts"] = frames[0].yarn_cp_counts;
  d["radius"] = frames[0].yarn_radius;
  d["times"] = times;
  d["samples"] = o.samples_per_segment;
  d["sides"] = o.sides;
  d["speed"] = 1.0;
  std::vector<int> rows;
  if (frames[0].stitch.size() == static_cast<size_t>(frames[0].num_seg()))
    for (const StitchCoord& s : frames[0].stitch) rows.push_back(s.row);
  d["rows"] = rows;
  d["positions"] = base64_of(q);
  d["box"] = {box.min().x(), box.min().y(), box.min().z(),
              box.max().x(), box.max().y(), box.max().z()};
  d["objects"] = objects;

  std::string html;
  html += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  html += "<title>" + html_escape(o.title) + "</title>\n";
  html += "<meta name=\"generator\" content=\"knitsim " KNIT_VERSION "\">\n";
  html +=
      "<style>\n"
      "html, body { margin: 0; height: 100%; overflow: hidden; font: 14px system-ui, "
      "sans-serif; background: #f4f1ea; }\n"
      "#view { display: block; width: 100%; height: calc(100% - 44px); }\n"
      "#bar { height: 44px; display: flex; align-items: center; gap: 12px; padding: 0 12px; "
      "box-sizing: border-box; }\n"
      "#frame { flex: 1; min-width: 60px; }\n"
      "#time, #title { white-space: nowrap; }\n"
      "#title { font-weight: 600; }\n"
      "#scale { position: absolute; right: 12px; bottom: 56px; color: #26262b; "
      "text-align: right; pointer-events: none; }\n"
      "#scale-bar { margin-left: auto; height: 7px; box-sizing: border-box; "
      "border: 2px solid #26262b; border-top: none; }\n"
      "</style>\n</head>\n<body>\n<canvas id=\"view\"></canvas>\n"
      "<div id=\"scale\"><div id=\"scale-label\"></div><div id=\"scale-bar\"></div></div>\n";
  html += "<div id=\"bar\"><span id=\"title\">" + html_escape(o.title) +
          "</span><button id=\"play\">play</button><input id=\"frame\" type=\"range\" min=\"0\" "
          "max=\"0\" step=\"1\" value=\"0\"><span id=\"time\"></span></div>\n";
  html += "<script type=\"application/json\" id=\"knitsim-data\">" + json_safe(d.dump()) +
          "</script>\n";
  html += "<script>\n" + three + "\n</script>\n";
  html += "<script>\n" + orbit + "\n</script>\n";
  html += "<script>\n";
  html += script_safe(VIEWER_JS);
  html += "</script>\n</body>\n</html>\n";
  return html;
}

}  // namespace knit
