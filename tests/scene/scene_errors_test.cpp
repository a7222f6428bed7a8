// Every kind of bad scene input is rejected with a message naming the file, the field and
// what was expected.
#include <gtest/gtest.h>

#include "knit/objects/object.hpp"
#include "knit/scene/json_reader.hpp"
#include "knit/scene/scene.hpp"

#include <fstream>

namespace knit {
namespace {

std::string error_of(const std::string& text) {
  try {
    parse_scene(nlohmann::json::parse(text), "scene.json");
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

void expect_error(const std::string& text, std::initializer_list<const char*> needles) {
  const std::string msg = error_of(text);
  ASSERT_FALSE(msg.empty()) << "accepted: " << text;
  EXPECT_NE(msg.find("scene.json"), std::string::npos) << msg;
  for (const char* n : needles)
    EXPECT_NE(msg.find(n), std::string::npos) << "'" << n << "' not in: " << msg;
}

const char* LINE = R"({"line": {"from": [0,0,0], "to": [4,0,0], "segments": 8}})";

std::string scene_with(const std::string& extra) {
  return std::string(R"({"yarns": [)") + LINE + "]" + extra + "}";
}

TEST(SceneErrors, ValidSceneParses) {
  const Scene s = parse_scene(
      nlohmann::json::parse(scene_with(R"(, "pins": [{"yarn": 0, "at": "start"}])")), "scene.json");
  EXPECT_EQ(s.model.num_seg(), 8);
  EXPECT_EQ(s.model.pins.size(), 1u);
  EXPECT_NEAR((point_position(s.model, s.state.q, {0, 0.0}) - Eigen::Vector3d::Zero()).norm(), 0,
              1e-12);
  EXPECT_NEAR((point_position(s.model, s.state.q, {7, 1.0}) - Eigen::Vector3d(4, 0, 0)).norm(), 0,
              1e-12);
}

TEST(SceneErrors, UnknownKeysAreNamed) {
  expect_error(scene_with(R"(, "gravty": [0,0,-981])"), {"gravty", "unknown key"});
  expect_error(scene_with(R"(, "params": {"k_bnd": 5})"), {"params.k_bnd", "unknown key"});
  expect_error(
      R"({"yarns": [{"line": {"from": [0,0,0], "to": [1,0,0], "segments": 4, "colour": 1}}]})",
      {"yarns[0].line.colour"});
}

TEST(SceneErrors, MissingFieldsAreNamed) {
  expect_error(R"({"time_step": 0.001})", {"yarns", "missing"});
  expect_error(R"({"yarns": [{"line": {"from": [0,0,0], "segments": 4}}]})",
               {"yarns[0].line.to", "missing"});
  expect_error(scene_with(R"(, "pins": [{"at": "start"}])"), {"pins[0].yarn", "missing"});
}

TEST(SceneErrors, NegativeOrNonFiniteParametersAreRejected) {
  expect_error(scene_with(R"(, "params": {"k_bend": -1})"), {"params.k_bend", "non-negative"});
  expect_error(scene_with(R"(, "params": {"radius": 0})"), {"params.radius", "positive"});
  expect_error(scene_with(R"(, "time_step": -0.001)"), {"time_step", "positive"});
  expect_error(scene_with(R"(, "params": {"alpha_small": 1.5})"), {"params.alpha_small", "[0, 1]"});
  expect_error(scene_with(R"(, "params": {"yarn_friction": -0.3})"),
               {"params.yarn_friction", "non-negative"});
  expect_error(scene_with(R"(, "params": {"yarn_friction": 30})"), {"yarn_friction", "[0, 10]"});
  expect_error(scene_with(R"(, "params": {"k_len": "stiff"})"), {"params.k_len", "number"});
  expect_error(scene_with(R"(, "params": {"integrator": "implicit"})"),
               {"params.integrator", "\"explicit\", \"imex\" or \"imex-contact\"", "implicit"});
  EXPECT_EQ(parse_scene(nlohmann::json::parse(scene_with(R"(, "params": {"integrator": "imex"})")),
                        "scene.json")
                .model.params.solver.integrator,
            Integrator::IMEX);
  expect_error(scene_with(R"(, "params": {"implicit_bending": 1})"),
               {"params.implicit_bending", "true or false"});
  EXPECT_TRUE(
      parse_scene(nlohmann::json::parse(scene_with(R"(, "params": {"implicit_bending": true})")),
                  "scene.json")
          .model.params.solver.implicit_bending);
  expect_error(scene_with(R"(, "params": {"max_step_halvings": 25})"),
               {"max_step_halvings", "[0, 20]"});
  expect_error(scene_with(R"(, "params": {"max_step_halvings": 1.5})"),
               {"params.max_step_halvings", "integer"});
  EXPECT_EQ(
      parse_scene(nlohmann::json::parse(scene_with(R"(, "params": {"max_step_halvings": 3})")),
                  "scene.json")
          .model.params.solver.max_step_halvings,
      3);
  expect_error(scene_with(R"(, "params": {"quadrature_points": 10})"),
               {"quadrature_points", "odd"});
  // JSON text has no NaN literal, but a document built in code can hold one
  nlohmann::json doc = nlohmann::json::parse(scene_with(""));
  doc["params"]["k_len"] = std::nan("");
  try {
    parse_scene(doc, "scene.json");
    FAIL() << "accepted NaN";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("params.k_len"), std::string::npos) << e.what();
  }
}

TEST(SceneErrors, PinsAndGlueMustReferToExistingYarnsAndSegments) {
  expect_error(scene_with(R"(, "pins": [{"yarn": 3, "at": "start"}])"),
               {"pins[0].yarn", "yarn 3 does not exist"});
  expect_error(scene_with(R"(, "pins": [{"yarn": 0, "segment": 8, "t": 0.5}])"),
               {"pins[0].segment", "segment 8 does not exist", "8 segments"});
  expect_error(scene_with(R"(, "pins": [{"yarn": 0, "segment": 2, "t": 1.5}])"),
               {"pins[0].t", "[0, 1]"});
  expect_error(scene_with(R"(, "pins": [{"yarn": 0, "at": "middle"}])"),
               {"pins[0].at", "\"start\" or \"end\""});
  expect_error(
      scene_with(R"(, "glue": [{"a": {"yarn": 0, "segment": 1}, "b": {"yarn": 1, "segment": 0}}])"),
      {"glue[0].b.yarn", "does not exist"});
}

TEST(SceneErrors, TooFewControlPoints) {
  expect_error(R"({"yarns": [{"points": [[0,0,0],[1,0,0],[2,0,0]]}]})",
               {"yarns[0].points", "at least 4 control points", "got 3"});
  expect_error(R"({"yarns": []})", {"yarns", "at least 1"});
  expect_error(R"({"yarns": [{"points": [[0,0,0],[1,0,0],[2,0],[3,0,0]]}]})",
               {"yarns[0].points[2]", "3 numbers"});
}

TEST(SceneErrors, MalformedJsonNamesLineAndColumn) {
  const std::string path = ::testing::TempDir() + "/bad_scene.json";
  {
    std::ofstream out(path);
    out << "{\n  \"yarns\": [\n    {\"line\": {\"from\": [0,0,0] \"to\": [1,0,0]}}\n  ]\n}\n";
  }
  try {
    load_scene(path);
    FAIL() << "accepted malformed JSON";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path + ":3:"), std::string::npos) << msg;
    EXPECT_NE(msg.find("malformed JSON"), std::string::npos) << msg;
  }
  EXPECT_THROW(load_scene(::testing::TempDir() + "/does_not_exist.json"), InputError);
  // a number too large for a double is a clear error too
  std::ofstream(path) << R"({"yarns": [], "time_step": 1e999})";
  try {
    load_scene(path);
    FAIL() << "accepted 1e999";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

// parsing is strict (docs/scene-format.md): a key given twice in one object is refused at
// its second place, named by field path, line and column; the same key in two objects is
// not a duplicate; the parser library's words are translated
TEST(SceneErrors, AKeyGivenTwiceIsRefusedWhereItIsGivenAgain) {
  auto error = [](const std::string& text) {
    try {
      parse_json_text(text, "s.json");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  EXPECT_EQ(error(R"({"a": {"b": 1}, "c": [{"b": 2}, {"b": 3}], "b": 4})"), "(accepted)");
  EXPECT_EQ(error("{\"yarns\": [{\"line\": {}},\n  {\"line\": {\"from\": 1, \"from\": 2}}]}"),
            "s.json:2:24: yarns[1].line.from: the key \"from\" is given twice in one object "
            "(each key may appear once)");
  EXPECT_NE(error(R"({"a": [[1, 2], {"x": 1, "x": 1}]})").find("a[1].x"), std::string::npos);
  // a key with bytes beyond ASCII is shown escaped
  const std::string accent = error("{\"\xc3\xa9k\": 1, \"\xc3\xa9k\": 2}");
  EXPECT_NE(accent.find("\"\\xC3\\xA9k\" is given twice"), std::string::npos) << accent;
  const std::string syntax = error("{\"a\": tru}");
  EXPECT_EQ(syntax.rfind("s.json:1:", 0), 0u) << syntax;
  EXPECT_NE(syntax.find("malformed JSON: invalid literal"), std::string::npos) << syntax;
  for (const char* library : {"json.exception", "parse error at", "syntax error while"})
    EXPECT_EQ(syntax.find(library), std::string::npos) << syntax;
  EXPECT_EQ(error("").find("json.exception"), std::string::npos);
}

TEST(SceneErrors, NumbersOutOfRangeAreNamedWithTheirValue) {
  expect_error(R"({"yarns": [{"line": {"from": [0,0,0], "to": [1,0,0], "segments": 2147483648}}]})",
               {"yarns[0].line.segments", "expected an integer from 1 to 200000, got 2147483648"});
  expect_error(R"({"yarns": [{"points": [[0,0,0],[1e300,0,0],[2,0,0],[3,0,0]]}]})",
               {"yarns[0].points[1][0]", "within ±1e+06 cm, got 1e+300"});
  expect_error(R"({"yarns": [{"points": [[0,0,0],[0,0,0],[0,0,0],[0,0,0],[1,0,0]]}]})",
               {"yarns[0]", "segment 0 has zero length"});
  expect_error(scene_with(R"(, "pins": [{"yarn": 0, "segment": 0, "t": -0.5}])"),
               {"pins[0].t", "expected t in [0, 1], got -0.5"});
  expect_error(scene_with(R"(, "output_every": 0)"), {"output_every", "got 0"});
  expect_error(scene_with(R"(, "params": {"quadrature_points": 4})"), {"odd", "got 4"});
  expect_error(scene_with(R"(, "params": {"alpha_large": 1.5})"),
               {"params.alpha_large", "alpha_large = 1.5", "[0, 1]"});
  expect_error(scene_with(R"(, "objects": [{"box": {"size": [1, 0, 3]}}])"),
               {"objects[0].box.size[1]", "got 0"});
}

TEST(SceneErrors, BadObjectsAreNamed) {
  auto objects = [](const std::string& list) { return scene_with(R"(, "objects": )" + list); };
  // a valid one of every shape parses
  const Scene ok = parse_scene(nlohmann::json::parse(objects(R"([
      {"name": "floor", "plane": {"normal": [0, 0, 1]}, "friction": 0.4},
      {"sphere": {"center": [0, 0, 5], "radius": 1}, "mechanism": "penalty", "stiffness": 1e4},
      {"box": {"size": [1, 2, 3]}, "position": [5, 0, 0], "rotate": {"axis": [0, 0, 1], "degrees": 30}},
      {"capsule": {"from": [0, 0, 0], "to": [0, 0, 2], "radius": 0.5}, "mechanism": "both"},
      {"cylinder": {"from": [0, 0, 0], "to": [0, 0, 2], "radius": 0.5}},
      {"ellipsoid": {"radii": [1, 2, 3]},
       "keyframes": [{"time": 0}, {"time": 1, "translate": [1, 0, 0]}]},
      {"smooth_union": {"blend": 0.5, "members": [{"sphere": {"radius": 1}},
                                                  {"union": {"members": [{"sphere": {"radius": 2}}]}}]}}
  ])")),
                               "scene.json");
  ASSERT_EQ(ok.model.objects.size(), 7u);
  EXPECT_EQ(ok.model.objects[0]->name, "floor");
  EXPECT_EQ(ok.model.objects[1]->name, "object1");
  EXPECT_TRUE(ok.model.objects[1]->penalty);
  EXPECT_FALSE(ok.model.objects[1]->filter);

  expect_error(objects(R"([{"torus": {"radius": 1}}])"),
               {"objects[0].torus", "unknown key", "sphere"});
  expect_error(objects(R"([{"name": "x"}])"), {"objects[0]", "expected a shape"});
  expect_error(objects(R"([{"sphere": {"radius": 1}, "mechanism": "penalty", "friction": 1}])"),
               {"objects[0].friction", "filter"});
  expect_error(objects(R"([{"sphere": {"radius": -1}}])"),
               {"objects[0].sphere.radius", "positive"});
  expect_error(objects(R"([{"sphere": {"radius": 1}, "cube": 1}])"), {"objects[0]", "cube"});
  expect_error(objects(R"([{"sphere": {"radius": 1}, "box": {"size": [1,1,1]}}])"),
               {"objects[0]", "one shape"});
  expect_error(objects(R"([{"sphere": {"radius": 1},
                            "keyframes": [{"time": 1}, {"time": 0.5}]}])"),
               {"objects[0].keyframes[1].time", "increase"});
  expect_error(objects(R"([{"mesh": {"path": "no_such_foot.obj"}}])"),
               {"objects[0].mesh.path", "no_such_foot.obj"});
  expect_error(objects(R"([{"plane": {"normal": [0, 0, 0]}}])"),
               {"objects[0].plane.normal", "zero"});
  expect_error(objects(R"([{"sphere": {"radius": 1}, "mechanism": "magnet"}])"),
               {"objects[0].mechanism", "magnet"});
  expect_error(objects(R"([{"sphere": {"radius": 1}, "stiffness": 5}])"),
               {"objects[0].stiffness", "penalty"});
  expect_error(objects(R"([{"sphere": {"radius": 1}, "friction": -0.5}])"),
               {"objects[0].friction"});
  expect_error(
      objects(
          R"([{"name": "a", "sphere": {"radius": 1}}, {"name": "a", "sphere": {"radius": 1}}])"),
      {"objects[1].name", "two objects"});
  expect_error(objects(R"([{"union": {"members": []}}])"), {"objects[0].union.members"});
  expect_error(objects(R"([{"union": {"members": [{"sphere": {"radius": 1}}], "blend": 1}}])"),
               {"objects[0].union.blend", "smooth_union"});
}

}  // namespace
}  // namespace knit
