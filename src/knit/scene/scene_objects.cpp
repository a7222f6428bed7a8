#include "knit/scene/scene_objects.hpp"
#include "knit/io/obj.hpp"

#include <cmath>
#include <filesystem>

#include "knit/model/params.hpp"
#include "knit/objects/mesh_shape.hpp"
#include "knit/scene/scene.hpp"

namespace knit {

namespace {

constexpr const char* SHAPE_KEYS[] = {"plane",     "sphere", "box",          "capsule", "cylinder",
                                      "ellipsoid", "union",  "smooth_union", "mesh"};
// largest coordinate or size an object may have (cm)
constexpr double MAX_EXTENT = MAX_SCENE_COORDINATE;

Eigen::Vector3d point(const JsonReader& r) {
  return r.coordinates(MAX_EXTENT);
}

double length(const JsonReader& r) {
  const double x = r.positive();
  if (!(x <= MAX_EXTENT))
    r.fail("expected at most " + short_number(MAX_EXTENT) + " cm, got " + short_number(x));
  return x;
}

Eigen::Vector3d lengths(const JsonReader& r) {
  const Eigen::Vector3d v = r.vec3();
  for (size_t k = 0; k < 3; ++k) {
    const double x = v[static_cast<Eigen::Index>(k)];
    if (!(x > 0) || !(x <= MAX_EXTENT))
      r.at(k).fail("expected a length in (0, " + short_number(MAX_EXTENT) + "] cm, got " +
                   short_number(x));
  }
  return v;
}

double in_range(const JsonReader& r, double lo, double hi, const char* unit) {
  const double x = r.number();
  if (!(x >= lo && x <= hi))
    r.fail("expected a value in [" + short_number(lo) + ", " + short_number(hi) + "] " + unit +
           ", got " + short_number(x));
  return x;
}

// the one shape key of `r` (an object or a union member)
std::string shape_key(const JsonReader& r) {
  std::string found;
  for (const char* key : SHAPE_KEYS)
    if (r.has(key)) {
      if (!found.empty()) r.fail("give one shape, not both \"" + found + "\" and \"" + key + "\"");
      found = key;
    }
  if (found.empty())
    r.fail(
        "expected a shape: one of \"plane\", \"sphere\", \"box\", \"capsule\", \"cylinder\", "
        "\"ellipsoid\", \"union\", \"smooth_union\", \"mesh\"");
  return found;
}

ShapePtr parse_shape(const JsonReader& holder, const std::string& scene_path, int depth);

std::vector<ShapePtr> parse_members(const JsonReader& list, const std::string& scene_path,
                                    int depth) {
  list.require_array(1);
  if (list.size() > static_cast<size_t>(MAX_SCENE_OBJECTS))
    list.fail("a union has at most " + std::to_string(MAX_SCENE_OBJECTS) + " members");
  std::vector<ShapePtr> members;
  for (size_t k = 0; k < list.size(); ++k) {
    const JsonReader m = list.at(k);
    m.require_object();
    const std::string key = shape_key(m);
    m.allow_keys({"plane", "sphere", "box", "capsule", "cylinder", "ellipsoid", "union",
                  "smooth_union", "mesh"});
    members.push_back(parse_shape(m, scene_path, depth + 1));
  }
  return members;
}

ShapePtr parse_shape(const JsonReader& holder, const std::string& scene_path, int depth) {
  if (depth > 8) holder.fail("unions nest at most 8 deep");
  const std::string key = shape_key(holder);
  const JsonReader r = holder.at(key);
  r.require_object();
  if (key == "plane") {
    r.allow_keys({"point", "normal"});
    const Eigen::Vector3d p = r.has("point") ? point(r.at("point")) : Eigen::Vector3d::Zero();
    const Eigen::Vector3d n = r.at("normal").vec3();
    if (!(n.norm() > 0)) r.at("normal").fail("the normal must not be zero");
    return make_plane(p, n);
  }
  if (key == "sphere") {
    r.allow_keys({"center", "radius"});
    return make_sphere(r.has("center") ? point(r.at("center")) : Eigen::Vector3d::Zero(),
                       length(r.at("radius")));
  }
  if (key == "box") {
    r.allow_keys({"center", "size"});
    return make_box(r.has("center") ? point(r.at("center")) : Eigen::Vector3d::Zero(),
                    0.5 * lengths(r.at("size")));
  }
  if (key == "capsule" || key == "cylinder") {
    r.allow_keys({"from", "to", "radius"});
    const Eigen::Vector3d a = point(r.at("from")), b = point(r.at("to"));
    const double radius = length(r.at("radius"));
    if (key == "capsule") return make_capsule(a, b, radius);
    if (!((b - a).norm() > 0)) r.at("to").fail("a cylinder's \"from\" and \"to\" must differ");
    return make_cylinder(a, b, radius);
  }
  if (key == "ellipsoid") {
    r.allow_keys({"center", "radii"});
    return make_ellipsoid(r.has("center") ? point(r.at("center")) : Eigen::Vector3d::Zero(),
                          lengths(r.at("radii")));
  }
  if (key == "union" || key == "smooth_union") {
    r.allow_keys({"members", "blend"});
    double blend = 0;
    if (key == "smooth_union") {
      blend = length(r.at("blend"));
    } else if (r.has("blend")) {
      r.at("blend").fail("\"blend\" belongs to a \"smooth_union\"");
    }
    return make_union(parse_members(r.at("members"), scene_path, depth), blend);
  }
  // mesh
  r.allow_keys({"path", "scale", "voxel_size"});
  const std::string path = r.at("path").string();
  const std::filesystem::path base = std::filesystem::path(scene_path).parent_path();
  const std::filesystem::path full =
      std::filesystem::path(path).is_absolute() ? std::filesystem::path(path) : base / path;
  const double scale = r.has("scale") ? in_range(r.at("scale"), 1e-6, 1e6, "") : 1.0;
  MeshGridOptions grid;
  if (r.has("voxel_size")) grid.voxel_size = in_range(r.at("voxel_size"), 1e-3, 100, "cm");
  TriangleMesh mesh;
  try {
    mesh = read_obj_mesh(full.string(), scale);
  } catch (const std::exception& e) {
    r.at("path").fail(e.what());
  }
  try {
    return make_mesh_shape(mesh, grid, full.string());
  } catch (const std::exception& e) {
    r.at("path").fail(e.what());
  }
}

}  // namespace

std::vector<std::shared_ptr<const SceneObject>> parse_objects(const JsonReader& list,
                                                              const std::string& scene_path) {
  list.require_array();
  if (list.size() > static_cast<size_t>(MAX_SCENE_OBJECTS))
    list.fail("a scene has at most " + std::to_string(MAX_SCENE_OBJECTS) + " objects");
  std::vector<std::shared_ptr<const SceneObject>> out;
  for (size_t k = 0; k < list.size(); ++k) {
    const JsonReader r = list.at(k);
    r.require_object();
    r.allow_keys({"name", "plane", "sphere", "box", "capsule", "cylinder", "ellipsoid", "union",
                  "smooth_union", "mesh", "position", "rotate", "keyframes", "mechanism",
                  "friction", "stiffness", "damping"});
    auto obj = std::make_shared<SceneObject>();
    obj->name = r.has("name") ? r.at("name").string() : "object" + std::to_string(k);
    if (obj->name.empty() || obj->name.find_first_of(",\"\n ") != std::string::npos)
      r.at("name").fail("an object's name must be non-empty, without spaces, commas or quotes");
    for (const auto& other : out)
      if (other->name == obj->name)
        r.at("name").fail("two objects are called \"" + obj->name + "\"");
    obj->shape = parse_shape(r, scene_path, 0);
    if (r.has("position")) obj->position = point(r.at("position"));
    if (r.has("rotate")) obj->rotation = parse_rotation(r.at("rotate"));
    if (r.has("keyframes")) obj->keyframes = parse_keyframes(r.at("keyframes"));
    if (r.has("mechanism")) {
      const std::string m = r.at("mechanism").string();
      if (m != "filter" && m != "penalty" && m != "both")
        r.at("mechanism").fail("expected \"filter\", \"penalty\" or \"both\", got \"" + m + "\"");
      obj->filter = m != "penalty";
      obj->penalty = m != "filter";
    }
    if (r.has("friction")) {
      if (!obj->filter)
        r.at("friction")
            .fail(
                "\"friction\" belongs to the filter: set \"mechanism\" to \"filter\" or \"both\"");
      obj->friction = in_range(r.at("friction"), 0, 100, "");
    }
    if (r.has("stiffness")) {
      if (!obj->penalty)
        r.at("stiffness")
            .fail(
                "\"stiffness\" belongs to the penalty: set \"mechanism\" to \"penalty\" or "
                "\"both\"");
      obj->stiffness = in_range(r.at("stiffness"), 1e-6, 1e9, "g/(cm s²)");
    }
    if (r.has("damping")) {
      if (!obj->penalty)
        r.at("damping").fail(
            "\"damping\" belongs to the penalty: set \"mechanism\" to \"penalty\" or \"both\"");
      obj->damping = in_range(r.at("damping"), 0, 1e6, "g/(cm s)");
    }
    out.push_back(obj);
  }
  return out;
}

std::vector<std::shared_ptr<const SceneObject>> load_scene_objects(const std::string& path) {
  const nlohmann::json doc = parse_json_file(path);
  const JsonReader root(doc, path);
  root.require_object();
  if (!root.has("objects")) return {};
  return parse_objects(root.at("objects"), path);
}

}  // namespace knit
