// libFuzzer target: the scene reader, as load_scene reads a file: parse_json_text (what
// parse_json_file does after its file checks) on the input, then parse_scene. Expected rejections
// are std::invalid_argument and std::runtime_error (InputError among them); any other exception, a
// crash, a sanitizer report or a hang is a bug.
//
// A scene names other files ("knits": [{"state": ...}], "yarns": [{"import": ...}]),
// relative to the scene's folder. The scene is placed in fuzz/scene_files/, which holds a
// few small files to name (a relaxed 2×2 knit, flat and in the round, and a yarn file of
// each kind); every path is read from that folder only: one that is absolute or has a
// '/' is replaced by "missing" before parsing, so no input makes the fuzzer read
// /dev/zero, a pipe or anything else outside it.

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <stdexcept>
#include <string>
#include <typeinfo>

#include "knit/scene/json_reader.hpp"
#include "knit/scene/scene.hpp"

#ifndef KNIT_FUZZ_SCENE_FILES
#error "KNIT_FUZZ_SCENE_FILES (the folder fuzz/scene_files) must be defined"
#endif

namespace {

void confine(nlohmann::json& path) {
  if (!path.is_string()) return;
  const std::string& s = path.get_ref<const std::string&>();
  if (s.empty() || s.find('/') != std::string::npos || s.find('\0') != std::string::npos ||
      s == "." || s == "..")
    path = "missing";
}

// a mesh's path anywhere in an object's shape (unions nest)
void confine_meshes(nlohmann::json& shape, int depth) {
  if (depth > 64) return;
  if (shape.is_array()) {
    for (auto& item : shape) confine_meshes(item, depth + 1);
    return;
  }
  if (!shape.is_object()) return;
  for (auto& [key, value] : shape.items()) {
    if (key == "mesh" && value.is_object() && value.contains("path")) confine(value["path"]);
    confine_meshes(value, depth + 1);
  }
}

// every place a scene names a file: knits[i].state, yarns[i].import, yarns[i].import.path,
// objects[i]…mesh.path
void confine_paths(nlohmann::json& doc) {
  if (!doc.is_object()) return;
  if (doc.contains("objects")) confine_meshes(doc["objects"], 0);
  for (const char* list : {"knits", "yarns"}) {
    if (!doc.contains(list) || !doc[list].is_array()) continue;
    for (auto& item : doc[list]) {
      if (!item.is_object()) continue;
      if (item.contains("state")) confine(item["state"]);
      if (item.contains("import")) {
        auto& imp = item["import"];
        confine(imp);
        if (imp.is_object() && imp.contains("path")) confine(imp["path"]);
      }
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string source = std::string(KNIT_FUZZ_SCENE_FILES) + "/scene.json";
  try {
    nlohmann::json doc =
        knit::parse_json_text(std::string(reinterpret_cast<const char*>(data), size), source);
    confine_paths(doc);
    const knit::Scene scene = knit::parse_scene(doc, source);
    // what a parsed scene promises: positions for every control point, at rest
    if (scene.state.q.size() != scene.model.num_dof() ||
        scene.state.v.size() != scene.state.q.size())
      __builtin_trap();
  } catch (const std::invalid_argument&) {
  } catch (const std::runtime_error&) {
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fuzz_scene: unexpected %s: %s\n", typeid(e).name(), e.what());
    std::abort();
  }
  return 0;
}
