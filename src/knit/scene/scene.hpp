#pragma once
// Scene files (JSON): yarns, parameters, pins and glue, time stepping. See
// docs/scene-format.md for the schema. Parsing is strict: unknown keys, missing fields,
// negative or non-finite parameters and references to yarns or segments that do not exist
// are InputErrors naming the file and the field.
#include <nlohmann/json.hpp>
#include <string>

#include "knit/model/model.hpp"
#include "knit/model/state.hpp"
#include "knit/scene/json_reader.hpp"

namespace knit {

struct Scene {
  Model model;
  State state;
  double time_step = 1.0 / 11800;  ///< s
  double duration = 1.0;           ///< s of simulated time
  int output_every = 100;          ///< steps between written states
};

/// Reads `params` (every key optional) over `base`.
Params parse_params(const JsonReader& reader, Params base);
/// Parses a scene document; `source` names it in error messages.
Scene parse_scene(const nlohmann::json& doc, const std::string& source);
/// Reads and parses a scene file.
Scene load_scene(const std::string& path);

}  // namespace knit
