#pragma once
// The "objects" list of a scene file (docs/scene-format.md, "Objects"): solid shapes the
// yarn collides with, each with its placement, motion and collision mechanism.
#include <memory>
#include <string>
#include <vector>

#include "knit/objects/object.hpp"
#include "knit/scene/json_reader.hpp"

namespace knit {

/// Most objects a scene may have, and members a union may have.
inline constexpr int MAX_SCENE_OBJECTS = 64;

/// Parses the "objects" array; mesh paths are taken from the folder of `scene_path`.
/// Throws InputError naming the field for anything wrong (unknown shape, a radius ≤ 0,
/// keyframes out of order, a missing or open mesh, …).
std::vector<std::shared_ptr<const SceneObject>> parse_objects(const JsonReader& list,
                                                              const std::string& scene_path);

/// The objects of a scene file alone (none when it has no "objects"), without reading its
/// yarns or knits: for drawing and exporting them.
std::vector<std::shared_ptr<const SceneObject>> load_scene_objects(const std::string& path);

}  // namespace knit
