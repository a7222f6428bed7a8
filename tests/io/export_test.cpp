#include "knit/io/export.hpp"
#include "knit/io/obj.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>

#include <nlohmann/json.hpp>

#include "io/external_readers.hpp"
#include "io/test_states.hpp"
#include "knit/io/import.hpp"
#include "knit/io/states.hpp"
#include "knit/objects/mesh_shape.hpp"
#include "knit/spline/fit.hpp"
#include "knit/util/process.hpp"

namespace knit {
namespace {

using test::BLENDER_MESH_REPORT;
using test::MeshReport;
using test::parse_mesh_report;
using test::run_blender;
using test::slurp;

// every "(x, y, z)" triple in `text`
std::vector<Eigen::Vector3d> parse_triples(const std::string& text) {
  std::vector<Eigen::Vector3d> out;
  static const std::regex triple(R"(\(([-0-9.e+]+), ([-0-9.e+]+), ([-0-9.e+]+)\))");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), triple);
       it != std::sregex_iterator(); ++it)
    out.emplace_back(std::stod((*it)[1]), std::stod((*it)[2]), std::stod((*it)[3]));
  return out;
}

// largest distance from any point of `b` to the polyline `a` (cm)
double max_distance_to_polyline(const Eigen::Matrix3Xd& a, const Eigen::Matrix3Xd& b) {
  double worst = 0;
  for (Eigen::Index j = 0; j < b.cols(); ++j) {
    double best = std::numeric_limits<double>::infinity();
    for (Eigen::Index i = 0; i + 1 < a.cols(); ++i) {
      const Eigen::Vector3d d = a.col(i + 1) - a.col(i);
      const double t = std::clamp((b.col(j) - a.col(i)).dot(d) / d.squaredNorm(), 0.0, 1.0);
      best = std::min(best, (a.col(i) + t * d - b.col(j)).norm());
    }
    worst = std::max(worst, best);
  }
  return worst;
}

TEST(ExportUsd, SingleFrameWritesTheExactCurves) {
  const StateFile s =
      test::state_of({test::helix_control_points(), test::helix_control_points(0.5)});
  const std::string usda = usda_text({s}, {0.0});
  for (const char* needle :
       {"#usda 1.0", "upAxis = \"Z\"", "metersPerUnit = 0.01", "def BasisCurves \"yarn_0\"",
        "def BasisCurves \"yarn_1\"", "uniform token type = \"cubic\"",
        "uniform token basis = \"bspline\"", "uniform token wrap = \"nonperiodic\"",
        "int[] curveVertexCounts = [27]", "float[] widths = [0.25, 0.25,",
        "interpolation = \"vertex\"", "color3f[] primvars:displayColor = [(",
        "vector3f[] velocities = [("})
    EXPECT_NE(usda.find(needle), std::string::npos) << "missing: " << needle;
  EXPECT_EQ(usda.find("timeSamples"), std::string::npos);
  // the points are the control points themselves (float precision), not a resampling
  const size_t at = usda.find("point3f[] points = ");
  ASSERT_NE(at, std::string::npos);
  const auto pts = parse_triples(usda.substr(at, usda.find('\n', at) - at));
  ASSERT_EQ(pts.size(), 27u);
  for (int k = 0; k < 27; ++k)
    EXPECT_LT((pts[k] - s.state.q.segment<3>(3 * k)).norm(), 1e-6) << "control point " << k;
}

TEST(ExportUsd, ColoursFollowTheRowsAndVelocitiesTheControlPoints) {
  StateFile s = test::state_of({test::helix_control_points()}, 0.125, 0, true);
  for (int k = 0; k < s.num_cp(); ++k) s.state.v.segment<3>(3 * k) = Eigen::Vector3d(k, -k, 0.5);
  const std::string usda = usda_text({s}, {0.0});
  auto array_of = [&](const std::string& name) {
    const size_t at = usda.find(name + " = [");
    EXPECT_NE(at, std::string::npos) << name;
    const size_t begin = at + name.size() + 4;
    return parse_triples(usda.substr(begin, usda.find(']', begin) - begin));
  };
  // rows are segment / 8: a colour per control point, the same along a row, changing
  // between rows
  const auto colours = array_of("primvars:displayColor");
  ASSERT_EQ(colours.size(), 27u);
  EXPECT_EQ(colours[0], colours[7]);
  EXPECT_NE(colours[7], colours[8]);
  const auto v = array_of("vector3f[] velocities");
  ASSERT_EQ(v.size(), 27u);
  for (int k = 0; k < 27; ++k) EXPECT_EQ(v[k], Eigen::Vector3d(k, -k, 0.5));
}

TEST(ExportUsd, SequenceBecomesTimeSamples) {
  std::vector<StateFile> frames;
  std::vector<double> times;
  for (int f = 0; f < 3; ++f) {
    StateFile s = test::helix_state(0.1 * f);
    s.state.q.array() += f;  // moves
    frames.push_back(s);
    times.push_back(0.1 * f);
  }
  const std::string usda = usda_text(frames, times);
  EXPECT_NE(usda.find("point3f[] points.timeSamples = {"), std::string::npos);
  EXPECT_NE(usda.find("endTimeCode = 2"), std::string::npos);
  EXPECT_NE(usda.find("timeCodesPerSecond = 10"), std::string::npos);
  const size_t ts = usda.find("points.timeSamples");
  for (int f = 0; f < 3; ++f)
    EXPECT_NE(usda.find("            " + std::to_string(f) + ": [(", ts), std::string::npos)
        << "frame " << f;
  // layouts must agree and times increase
  frames[1] = test::state_of({test::helix_control_points(1, 1, 3, 20)});
  EXPECT_THROW(usda_text(frames, times), std::invalid_argument);
  EXPECT_THROW(usda_text({test::helix_state(), test::helix_state()}, {1.0, 1.0}),
               std::invalid_argument);
}

TEST(ExportObj, BlenderImportsIt) {
  KNIT_REQUIRE_READER(blender, "blender", "blender");
  const StateFile s =
      test::state_of({test::helix_control_points(), test::helix_control_points(0.5)});
  const auto dir = test::temp_dir("obj-blender");
  const std::string obj = (dir / "two.obj").string();
  export_obj(s, obj, 8);
  const std::string script = std::string(
                                 "import bpy, sys\n"
                                 "bpy.ops.wm.read_factory_settings(use_empty=True)\n"
                                 "bpy.ops.wm.obj_import(filepath=sys.argv[-1], forward_axis='Y', "
                                 "up_axis='Z')\n") +
                             BLENDER_MESH_REPORT;
  int rc = 0;
  std::string messages;
  const auto meshes = parse_mesh_report(run_blender(blender, dir, script, obj, rc, messages));
  ASSERT_EQ(rc, 0) << messages;
  // one polyline object per yarn, every sample a vertex and every span an edge, where
  // the samples are
  const auto samples = sample_yarns(s, 8);
  ASSERT_EQ(meshes.size(), 2u) << messages;
  for (int y = 0; y < 2; ++y) {
    EXPECT_EQ(meshes[y].name, "yarn_" + std::to_string(y));
    EXPECT_EQ(meshes[y].vertices, samples[y].cols());
    EXPECT_EQ(meshes[y].edges, samples[y].cols() - 1);
    EXPECT_LT((meshes[y].lo - samples[y].rowwise().minCoeff()).cwiseAbs().maxCoeff(), 1e-4);
    EXPECT_LT((meshes[y].hi - samples[y].rowwise().maxCoeff()).cwiseAbs().maxCoeff(), 1e-4);
  }
  std::filesystem::remove_all(dir);
}

TEST(ExportPly, BlenderImportsIt) {
  KNIT_REQUIRE_READER(blender, "blender", "blender");
  const StateFile s =
      test::state_of({test::helix_control_points(), test::helix_control_points(0.5)});
  const auto dir = test::temp_dir("ply-blender");
  const std::string script = std::string(
                                 "import bpy, sys\n"
                                 "bpy.ops.wm.read_factory_settings(use_empty=True)\n"
                                 "bpy.ops.import_mesh.ply(filepath=sys.argv[-1])\n") +
                             BLENDER_MESH_REPORT;
  const auto samples = sample_yarns(s, 8);
  const long nv = samples[0].cols() + samples[1].cols();
  const Eigen::Vector3d lo =
      samples[0].rowwise().minCoeff().cwiseMin(samples[1].rowwise().minCoeff());
  const Eigen::Vector3d hi =
      samples[0].rowwise().maxCoeff().cwiseMax(samples[1].rowwise().maxCoeff());
  for (bool binary : {true, false}) {
    SCOPED_TRACE(binary ? "binary" : "ascii");
    const std::string ply = (dir / (binary ? "bin.ply" : "ascii.ply")).string();
    export_ply(s, ply, binary, 8);
    int rc = 0;
    std::string messages;
    const auto meshes = parse_mesh_report(run_blender(blender, dir, script, ply, rc, messages));
    ASSERT_EQ(rc, 0) << messages;
    // one mesh: both yarns' samples as vertices, their spans as edges
    ASSERT_EQ(meshes.size(), 1u) << messages;
    EXPECT_EQ(meshes[0].vertices, nv);
    EXPECT_EQ(meshes[0].edges, nv - 2);
    EXPECT_LT((meshes[0].lo - lo).cwiseAbs().maxCoeff(), 1e-4);
    EXPECT_LT((meshes[0].hi - hi).cwiseAbs().maxCoeff(), 1e-4);
  }
  std::filesystem::remove_all(dir);
}

TEST(ExportUsd, BlenderImportsIt) {
  KNIT_REQUIRE_READER(blender, "blender", "blender");
  const auto dir = test::temp_dir("usd-blender");
  const std::string usd = (dir / "helix.usda").string();
  export_usd({test::helix_state()}, {0.0}, usd);
  // exit status 77: this Blender has no USD importer (Debian's is built without USD)
  const std::string script =
      "import bpy, sys\n"
      "if not bpy.app.build_options.usd:\n"
      "    sys.exit(77)\n"
      "bpy.ops.wm.read_factory_settings(use_empty=True)\n"
      "bpy.ops.wm.usd_import(filepath=sys.argv[-1])\n"
      "n = len(bpy.data.objects)\n"
      "open(sys.argv[-2], 'w').write('imported objects: %d\\n' % n)\n"
      "sys.exit(0 if n > 0 else 3)\n";
  int rc = 0;
  std::string messages;
  run_blender(blender, dir, script, usd, rc, messages);
  std::filesystem::remove_all(dir);
  if (rc == 77)
    GTEST_SKIP() << blender
                 << " was built without USD support (as Debian's is): the .usda is checked by "
                    "the other ExportUsd tests only";
  EXPECT_EQ(rc, 0) << messages;
}

// The .usda read by an independent parser (three.js's USDA parser, run by Node): the
// stage's units and axis, one BasisCurves prim per yarn with a point, width, colour and
// velocity per control point, the points time-sampled per frame, an object's Mesh prim.
TEST(ExportUsd, ThreeJsUsdaParserReadsIt) {
  KNIT_REQUIRE_READER(node, "node", "nodejs");
  const std::filesystem::path parser =
      std::filesystem::path(KNIT_SOURCE_DIR) / "third_party/three-usda/USDAParser.js";
  if (!std::filesystem::exists(parser)) {
    if (test::readers_skip_requested()) GTEST_SKIP() << "KNIT_SKIP_READERS is set";
    FAIL() << parser << " is missing: scripts/fetch-usda-parser.sh fetches it (scripts/test.sh "
           << "runs it)";
  }
  std::vector<StateFile> frames;
  for (int f = 0; f < 3; ++f) {
    StateFile s = test::state_of(
        {test::helix_control_points(), test::helix_control_points(0.5, 1, 2, 30)}, 0.125, 0, true);
    s.state.q.array() += 0.5 * f;
    s.state.time = 0.1 * f;
    frames.push_back(s);
  }
  auto ball = std::make_shared<SceneObject>();
  ball->name = "ball";
  ball->shape = make_sphere(Eigen::Vector3d::Zero(), 1);
  const auto dir = test::temp_dir("usd-three");
  const std::string usd = (dir / "run.usda").string();
  export_usd(frames, {0.0, 0.1, 0.2}, usd, {ball});
  std::string messages;
  const int rc = run_process({node, std::string(KNIT_SOURCE_DIR) + "/tests/io/usda_check.mjs",
                              parser.string(), usd, (dir / "parsed.json").string()},
                             messages);
  const std::string out = slurp(dir / "parsed.json");
  std::filesystem::remove_all(dir);
  ASSERT_EQ(rc, 0) << messages;
  const nlohmann::json j = nlohmann::json::parse(out);
  EXPECT_EQ(j["root"]["upAxis"], "Z");
  EXPECT_DOUBLE_EQ(j["root"]["metersPerUnit"].get<double>(), 0.01);
  const auto& specs = j["specs"];
  std::vector<std::string> curves, meshes;
  for (const auto& [path, spec] : specs.items()) {
    const std::string type = spec["fields"].value("typeName", "");
    if (spec["specType"] == 6 && type == "BasisCurves") curves.push_back(path);
    if (spec["specType"] == 6 && type == "Mesh") meshes.push_back(path);
  }
  ASSERT_EQ(curves.size(), 2u) << out.substr(0, 2000);
  EXPECT_EQ(meshes.size(), 1u);
  std::sort(curves.begin(), curves.end());
  for (int y = 0; y < 2; ++y) {
    const std::string& c = curves[y];
    EXPECT_EQ(c.substr(c.rfind('/')), "/yarn_" + std::to_string(y));
    const long n = frames[0].yarn_cp_counts[y];
    auto field = [&](const std::string& attr) -> const nlohmann::json& {
      const std::string key = c + "." + attr;
      EXPECT_TRUE(specs.contains(key)) << key;
      return specs.contains(key) ? specs[key]["fields"] : specs["/"]["fields"];
    };
    EXPECT_EQ(field("type")["default"], "cubic");
    EXPECT_EQ(field("basis")["default"], "bspline");
    EXPECT_EQ(field("wrap")["default"], "nonperiodic");
    EXPECT_EQ(field("curveVertexCounts")["default"], nlohmann::json::array({n}));
    // (the parser flattens arrays of tuples: 3 numbers per point)
    EXPECT_EQ(field("widths")["default"].size(), static_cast<size_t>(n));
    EXPECT_EQ(field("primvars:displayColor")["default"].size(), static_cast<size_t>(3 * n));
    const auto& samples = field("points")["timeSamples"];
    ASSERT_EQ(samples["times"], nlohmann::json::array({0, 1, 2}));
    for (int f = 0; f < 3; ++f) {
      const auto& pts = samples["values"][f];
      ASSERT_EQ(pts.size(), static_cast<size_t>(3 * n)) << "frame " << f;
      const Eigen::Index first = 3 * frames[f].yarn_cp_begin()[y];
      for (Eigen::Index k = 0; k < 3 * n; ++k)
        ASSERT_NEAR(pts[k].get<double>(), frames[f].state.q[first + k], 1e-5) << k;
    }
    EXPECT_EQ(field("velocities")["timeSamples"]["values"][2].size(), static_cast<size_t>(3 * n));
  }
}

// An object's surface as OBJ opens in Blender as one closed mesh: every vertex, every edge
// shared by two triangles (E = 3T/2), where the sphere is.
TEST(ExportObjectMesh, BlenderImportsAClosedSurface) {
  KNIT_REQUIRE_READER(blender, "blender", "blender");
  const ShapePtr ball = make_sphere(Eigen::Vector3d(1, 2, 3), 2);
  const TriangleMesh m = surface_mesh(
      *ball, Eigen::AlignedBox3d(Eigen::Vector3d::Constant(-5), Eigen::Vector3d::Constant(8)),
      0.25);
  ASSERT_EQ(open_edges(m), 0);
  const auto dir = test::temp_dir("mesh-blender");
  const std::string obj = (dir / "ball.obj").string();
  write_obj_mesh(m, obj);
  const std::string script = std::string(
                                 "import bpy, sys\n"
                                 "bpy.ops.wm.read_factory_settings(use_empty=True)\n"
                                 "bpy.ops.wm.obj_import(filepath=sys.argv[-1], forward_axis='Y', "
                                 "up_axis='Z')\n") +
                             BLENDER_MESH_REPORT;
  int rc = 0;
  std::string messages;
  const auto meshes = parse_mesh_report(run_blender(blender, dir, script, obj, rc, messages));
  ASSERT_EQ(rc, 0) << messages;
  ASSERT_EQ(meshes.size(), 1u) << messages;
  EXPECT_EQ(meshes[0].vertices, static_cast<long>(m.vertices.size()));
  EXPECT_EQ(2 * meshes[0].edges, 3 * static_cast<long>(m.triangles.size()));
  EXPECT_LT((meshes[0].lo - Eigen::Vector3d(-1, 0, 1)).cwiseAbs().maxCoeff(), 0.02);
  EXPECT_LT((meshes[0].hi - Eigen::Vector3d(3, 4, 5)).cwiseAbs().maxCoeff(), 0.02);
  std::filesystem::remove_all(dir);
}

// Objects in the USD: one Mesh prim each after the curves, its indices within its points,
// a moving object's pose time-sampled with the curves.
TEST(ExportUsd, ObjectsBecomeMeshPrimsWithTheirMotion) {
  const StateFile a = test::state_of({test::helix_control_points()});
  StateFile b = a;
  b.state.time = 0.5;
  auto ball = std::make_shared<SceneObject>();
  ball->name = "ball";
  ball->shape = make_sphere(Eigen::Vector3d::Zero(), 1);
  Keyframe k0, k1;
  k1.time = 1;
  k1.translation = Eigen::Vector3d(4, 0, 0);
  ball->keyframes = {k0, k1};
  auto floor = std::make_shared<SceneObject>();
  floor->name = "floor-1";
  floor->shape = make_plane(Eigen::Vector3d(0, 0, -3), Eigen::Vector3d::UnitZ());
  const std::string text = usda_text({a, b}, {0.0, 0.5}, {ball, floor});
  ASSERT_NE(text.find("def Mesh \"object_ball\""), std::string::npos);
  ASSERT_NE(text.find("def Mesh \"object_floor_1\""), std::string::npos) << "a valid prim name";
  EXPECT_LT(text.find("def BasisCurves"), text.find("def Mesh"));
  // the ball's prim: counts and indices agree, its translation moves 2 cm by t = 0.5 s
  const size_t at = text.find("def Mesh \"object_ball\"");
  const std::string prim = text.substr(at, text.find("def Mesh", at + 10) - at);
  // (std::regex recurses per character: too deep for a prim of many thousand numbers)
  auto list_after = [&](const std::string& key) {
    const size_t k = prim.find(key);
    EXPECT_NE(k, std::string::npos) << key;
    const size_t open = prim.find('[', k + key.size()), close = prim.find(']', open);
    return prim.substr(open + 1, close - open - 1);
  };
  const std::string c = list_after("faceVertexCounts = "), ix = list_after("faceVertexIndices = "),
                    pts = list_after("point3f[] points = ");
  const long faces = std::count(c.begin(), c.end(), '3');
  const long n_idx = std::count(ix.begin(), ix.end(), ',') + 1;
  const long n_pts = std::count(pts.begin(), pts.end(), '(');
  EXPECT_GT(faces, 100);
  EXPECT_EQ(n_idx, 3 * faces);
  long max_index = 0;
  std::istringstream in(ix);
  for (std::string tok; std::getline(in, tok, ',');)
    max_index = std::max(max_index, std::stol(tok));
  EXPECT_LT(max_index, n_pts);
  EXPECT_NE(prim.find("xformOp:translate.timeSamples"), std::string::npos);
  EXPECT_NE(prim.find("1: (2, 0, 0)"), std::string::npos)
      << prim.substr(prim.find("timeSamples"), 200);
  // the floor does not move: no time samples
  const std::string floor_prim = text.substr(text.find("def Mesh \"object_floor_1\""));
  EXPECT_EQ(floor_prim.find("timeSamples"), std::string::npos);
}

// One entry point writes every format (the CLI's export and --export use it): a file with
// the format's extension and its signature; an unknown format is refused by name.
TEST(ExportState, EveryFormatWritesItsFile) {
  const auto dir = test::temp_dir("export-state");
  const StateFile s = test::helix_state();
  const std::map<std::string, std::string> signature = {
      {"usd", "#usda 1.0"}, {"obj", "o yarn_0"}, {"bcc", "BCC"},        {"ply", "ply\n"},
      {"vtp", "<?xml"},     {"obj-mesh", "o "},  {"ply-mesh", "ply\n"}, {"glb", "glTF"}};
  for (const std::string& format : export_formats()) {
    const auto path = dir / ("out-" + format + export_extension(format));
    export_state(s, format, path.string());
    const std::string text = slurp(path);
    ASSERT_TRUE(signature.count(format)) << format;
    EXPECT_NE(text.find(signature.at(format)), std::string::npos) << format;
    EXPECT_LT(text.find(signature.at(format)), 200u) << format;
  }
  EXPECT_EQ(export_extension("usd"), ".usda");
  EXPECT_EQ(export_extension("ply-mesh"), ".ply");
  try {
    export_state(s, "stl", (dir / "x.stl").string());
    ADD_FAILURE() << "stl accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'stl'"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "x.stl"));
  std::filesystem::remove_all(dir);
}

TEST(ExportObj, RoundTripReproducesTheCurve) {
  const StateFile s = test::helix_state();
  const std::string text = obj_text(s, 8);
  EXPECT_NE(text.find("o yarn_0"), std::string::npos);
  const auto raw = parse_obj(text, "helix.obj");
  ASSERT_EQ(raw.size(), 1u);
  EXPECT_EQ(raw[0].points.cols(), 24 * 8 + 1);
  ImportOptions opt;
  opt.segments_per_cm = 24 / polyline_length(raw[0].points);
  const auto fitted = fit_yarns(raw, opt, "helix.obj");
  ASSERT_EQ(fitted.size(), 1u);
  EXPECT_EQ(fitted[0].control_points.cols(), 27);
  EXPECT_DOUBLE_EQ(fitted[0].radius, 0.125);
  // the refit curve stays within a small fraction of the radius of the original
  const Eigen::Matrix3Xd original = sample_bspline(yarn_control_points(s)[0], 32);
  const double err =
      max_distance_to_polyline(original, sample_bspline(fitted[0].control_points, 8));
  RecordProperty("obj_roundtrip_error_cm", std::to_string(err));
  EXPECT_LT(err, 0.05 * 0.125);
}

TEST(ExportBcc, HeaderAndRoundTrip) {
  const StateFile s =
      test::state_of({test::helix_control_points(), test::helix_control_points(0.5)});
  const auto dir = test::temp_dir("bcc");
  export_bcc(s, (dir / "two.bcc").string(), 8);
  const std::string bytes = slurp(dir / "two.bcc");
  const size_t n = 24 * 8 + 1;
  ASSERT_EQ(bytes.size(), 64 + 2 * (4 + 12 * n));
  EXPECT_EQ(bytes.substr(0, 3), "BCC");
  EXPECT_EQ(static_cast<unsigned char>(bytes[3]), 0x44);
  EXPECT_EQ(bytes.substr(4, 2), "PL");
  EXPECT_EQ(bytes[6], 3);
  uint64_t curves, points;
  std::memcpy(&curves, bytes.data() + 8, 8);
  std::memcpy(&points, bytes.data() + 16, 8);
  EXPECT_EQ(curves, 2u);
  EXPECT_EQ(points, 2 * n);
  const auto raw = parse_bcc(bytes, "two.bcc");
  ASSERT_EQ(raw.size(), 2u);
  const auto original = sample_yarns(s, 8);
  for (int y = 0; y < 2; ++y) EXPECT_LT((raw[y].points - original[y]).cwiseAbs().maxCoeff(), 1e-6);
  ImportOptions opt;
  opt.segments_per_cm = 24 / polyline_length(raw[0].points);
  const auto fitted = fit_yarns({raw[0]}, opt, "two.bcc");
  const double err = max_distance_to_polyline(sample_bspline(yarn_control_points(s)[0], 32),
                                              sample_bspline(fitted[0].control_points, 8));
  EXPECT_LT(err, 0.05 * 0.125);
}

TEST(ExportPly, BinaryAndAsciiLayouts) {
  const StateFile s = test::helix_state();
  const long nv = 24 * 8 + 1, ne = nv - 1;
  const std::string bin = ply_bytes(s, true, 8);
  const size_t end = bin.find("end_header\n");
  ASSERT_NE(end, std::string::npos);
  EXPECT_NE(bin.find("format binary_little_endian 1.0"), std::string::npos);
  EXPECT_NE(bin.find("element vertex " + std::to_string(nv)), std::string::npos);
  EXPECT_NE(bin.find("element edge " + std::to_string(ne)), std::string::npos);
  EXPECT_EQ(bin.size(), end + 11 + nv * 20 + ne * 8);
  float x;
  std::memcpy(&x, bin.data() + end + 11, 4);
  EXPECT_NEAR(x, sample_yarns(s, 8)[0](0, 0), 1e-6);
  const std::string ascii = ply_bytes(s, false, 8);
  const std::string body = ascii.substr(ascii.find("end_header\n") + 11);
  EXPECT_EQ(std::count(body.begin(), body.end(), '\n'), nv + ne);
}

TEST(ExportCli, FormatsFilesAndDirectories) {
  const auto dir = test::temp_dir("export-cli");
  for (int f = 0; f < 2; ++f)
    write_state_file((dir / ("s" + std::to_string(f) + ".kstate")).string(),
                     test::helix_state(0.5 * f));
  const std::string app = KNIT_APP;
  auto run = [&](std::vector<std::string> args, std::string& messages) {
    args.insert(args.begin(), app);
    return run_process(args, messages);
  };
  std::string msg;
  for (const char* fmt : {"usd", "obj", "bcc", "ply"}) {
    const std::string out = (dir / (std::string("one.") + fmt)).string();
    EXPECT_EQ(run({"export", (dir / "s0.kstate").string(), "--format", fmt, "--out", out}, msg), 0)
        << msg;
    EXPECT_TRUE(std::filesystem::exists(out)) << fmt;
  }
  // a directory: USD gets time samples, OBJ one file per state
  const std::string seq = (dir / "seq.usda").string();
  std::filesystem::create_directories(dir / "states");
  for (int f = 0; f < 2; ++f)
    std::filesystem::copy(dir / ("s" + std::to_string(f) + ".kstate"), dir / "states");
  EXPECT_EQ(run({"export", (dir / "states").string(), "--format", "usd", "--out", seq}, msg), 0)
      << msg;
  EXPECT_NE(slurp(seq).find("points.timeSamples"), std::string::npos);
  EXPECT_EQ(run({"export", (dir / "states").string(), "--format", "obj", "--out",
                 (dir / "objs").string()},
                msg),
            0)
      << msg;
  EXPECT_TRUE(std::filesystem::exists(dir / "objs" / "s1.obj"));
  EXPECT_EQ(run({"export", (dir / "states").string(), "--format", "obj", "--out", seq}, msg), 1);
  EXPECT_NE(msg.find("knitsim: error:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("one file per state"), std::string::npos) << msg;
  // the tube meshes and VTP, one file and a directory (named .obj / .ply per state)
  for (const auto& [fmt, ext] : std::vector<std::pair<std::string, std::string>>{
           {"vtp", ".vtp"}, {"obj-mesh", ".obj"}, {"ply-mesh", ".ply"}, {"glb", ".glb"}}) {
    const std::string out = (dir / ("tube" + ext)).string();
    EXPECT_EQ(run({"export", (dir / "s0.kstate").string(), "--format", fmt, "--out", out}, msg), 0)
        << msg;
    EXPECT_TRUE(std::filesystem::exists(out)) << fmt;
    const auto each = dir / ("each-" + fmt);
    EXPECT_EQ(
        run({"export", (dir / "states").string(), "--format", fmt, "--out", each.string()}, msg), 0)
        << msg;
    EXPECT_TRUE(std::filesystem::exists(each / ("s1" + ext))) << fmt;
  }
  // Y up in metres: the OBJ's vertices are (x, z, −y) / 100 of the default's
  const std::string zup = (dir / "zup.obj").string(), yup = (dir / "yup.obj").string();
  ASSERT_EQ(run({"export", (dir / "s0.kstate").string(), "--format", "obj", "--out", zup}, msg), 0);
  ASSERT_EQ(run({"export", (dir / "s0.kstate").string(), "--format", "obj", "--y-up", "--metres",
                 "--out", yup},
                msg),
            0)
      << msg;
  auto vertices = [&](const std::string& path) {
    std::vector<Eigen::Vector3d> v;
    std::istringstream in(slurp(path));
    for (std::string line; std::getline(in, line);)
      if (line.rfind("v ", 0) == 0) {
        std::istringstream l(line.substr(2));
        Eigen::Vector3d p;
        l >> p.x() >> p.y() >> p.z();
        v.push_back(p);
      }
    return v;
  };
  const auto a = vertices(zup), b = vertices(yup);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_FALSE(a.empty());
  for (size_t k = 0; k < a.size(); k += 17)
    EXPECT_LT((b[k] - Eigen::Vector3d(a[k].x(), a[k].z(), -a[k].y()) / 100).norm(), 1e-7) << k;
  EXPECT_EQ(run({"export", (dir / "s0.kstate").string(), "--format", "glb", "--y-up", "--out",
                 (dir / "y.glb").string()},
                msg),
            1);
  // an output named for another format is refused, and nothing is written
  for (const auto& [fmt, name, why] : std::vector<std::array<std::string, 3>>{
           {"usd", "x.usdc", "USD's binary crate format"},
           {"usd", "x.usdz", "zip package"},
           {"glb", "x.gltf", "the glb format writes a .glb file"},
           {"obj-mesh", "x.ply", "writes a .obj file"},
           {"ply", "x", "got no extension"}}) {
    const std::string out = (dir / name).string();
    EXPECT_EQ(run({"export", (dir / "s0.kstate").string(), "--format", fmt, "--out", out}, msg), 1)
        << name;
    EXPECT_NE(msg.find(why), std::string::npos) << msg;
    EXPECT_FALSE(std::filesystem::exists(out)) << name;
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace knit
