#pragma once
// Scene files (JSON): yarns, relaxed knits, parameters, pins, glue and clamps, time
// stepping. See
// docs/scene-format.md for the schema. Parsing is strict: unknown keys, missing fields,
// negative or non-finite parameters and references to yarns or segments that do not exist
// are InputErrors naming the file and the field.
#include <nlohmann/json.hpp>
#include <string>

#include "knit/model/model.hpp"
#include "knit/model/state.hpp"
#include "knit/scene/json_reader.hpp"

namespace knit {

/// A relaxed knit placed in a scene: its yarn and how its stitches wrap.
struct SceneKnit {
  std::string source;  ///< the .kstate it was read from
  int yarn = 0;        ///< its yarn in the model
  bool in_the_round = false;
};

struct Scene {
  Model model;  ///< its params.solver.time_step is the scene's time step
  State state;
  double duration = 1.0;   ///< s of simulated time
  int output_every = 100;  ///< steps between written states
  std::vector<SceneKnit> knits;
};

/// A rotation {"axis": [x, y, z], "degrees": a} (a non-zero axis, |a| ≤ 1e6).
Eigen::Quaterniond parse_rotation(const JsonReader& reader);
/// Keyframes [{"time": t, "translate": [x, y, z], "rotate": {…}}, …]: at least one, times
/// in [0, MAX_DURATION] and increasing, translations within ±1e6 cm (clamps and objects).
std::vector<Keyframe> parse_keyframes(const JsonReader& reader);

/// Reads `params` (every key optional) over `base`.
Params parse_params(const JsonReader& reader, Params base);
/// Parses a scene document; `source` names it in error messages (and relative paths in it
/// are taken from its folder). `base` is what "params" is read over.
Scene parse_scene(const nlohmann::json& doc, const std::string& source,
                  const Params& base = Params::simulation());
/// The scene {"knits": [{"state": kstate_path}]} with `params`: a relaxed knit (written by
/// `knitsim relax`) at rest where it was relaxed, its rest lengths those of the relaxed
/// yarn, its glues holding.
Scene scene_from_knit_state(const std::string& kstate_path, const Params& params);
/// Reads and parses a scene file.
Scene load_scene(const std::string& path);
/// Reads a scene file with one knit and places the relaxed knit of `kstate_path` (a path
/// as given on a command line) where the scene's knit is, instead of the state it names.
Scene load_scene_with_knit(const std::string& path, const std::string& kstate_path);

}  // namespace knit
