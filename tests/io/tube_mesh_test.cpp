// Yarn tube meshes and VTK PolyData: their geometry by measurement, and each format opened
// in the real reader a user would open it in (Blender for OBJ and PLY meshes, Assimp for
// glTF, VTK for VTP).
#include "knit/io/tube_mesh.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <regex>

#include "io/external_readers.hpp"
#include "io/test_states.hpp"
#include "knit/io/export.hpp"
#include "knit/io/states.hpp"
#include "knit/util/atomic_file.hpp"

namespace knit {
namespace {

using test::slurp;

StateFile two_helices() {
  StateFile s = test::state_of({test::helix_control_points(), test::helix_control_points(0.5)},
                               0.125, 0.25, true);
  // a rigid spin about x (ω = 2 /s): v = ω × q
  for (int k = 0; k < s.num_cp(); ++k) {
    const Eigen::Vector3d q = s.state.q.segment<3>(3 * k);
    s.state.v.segment<3>(3 * k) = Eigen::Vector3d(2, 0, 0).cross(q);
  }
  return s;
}

// length of a sampled centreline
double polyline_length(const Eigen::Matrix3Xd& p) {
  double L = 0;
  for (Eigen::Index k = 0; k + 1 < p.cols(); ++k) L += (p.col(k + 1) - p.col(k)).norm();
  return L;
}

TEST(TubeMesh, EachTubeIsClosedOutwardAndHoldsItsPolygonTimesItsLength) {
  const StateFile s = two_helices();
  const int per = 8, sides = 12;
  const TubeMesh m = tube_mesh(s, per, sides);
  const auto samples = sample_yarns(s, per);
  ASSERT_EQ(m.num_yarns(), 2);
  for (int y = 0; y < 2; ++y) {
    SCOPED_TRACE(y);
    const long rings = samples[y].cols();
    EXPECT_EQ(m.vertex_begin[y + 1] - m.vertex_begin[y], rings * sides + 2 * (sides + 1));
    EXPECT_EQ(m.triangle_begin[y + 1] - m.triangle_begin[y], 2 * (rings - 1) * sides + 2 * sides);
    // the caps copy the end rings' positions: welded by position, every edge joins two
    // triangles that run it in opposite directions (closed and consistently oriented)
    std::map<std::array<float, 3>, int> id;
    auto weld = [&](int v) {
      const Eigen::Vector3f& p = m.positions[v];
      return id.emplace(std::array<float, 3>{p.x(), p.y(), p.z()}, static_cast<int>(id.size()))
          .first->second;
    };
    std::map<std::pair<int, int>, int> directed;
    double volume = 0;
    for (int t = m.triangle_begin[y]; t < m.triangle_begin[y + 1]; ++t) {
      const Eigen::Vector3i& tri = m.triangles[t];
      for (int c = 0; c < 3; ++c) ++directed[{weld(tri[c]), weld(tri[(c + 1) % 3])}];
      const Eigen::Vector3d a = m.positions[tri[0]].cast<double>(),
                            b = m.positions[tri[1]].cast<double>(),
                            c = m.positions[tri[2]].cast<double>();
      volume += a.dot(b.cross(c)) / 6;
      // the vertex normals lean the way the triangle faces
      const Eigen::Vector3d face = (b - a).cross(c - a);
      const Eigen::Vector3d normal =
          (m.normals[tri[0]] + m.normals[tri[1]] + m.normals[tri[2]]).cast<double>();
      EXPECT_GT(face.dot(normal), 0) << "triangle " << t;
    }
    for (const auto& [edge, count] : directed) {
      EXPECT_EQ(count, 1);
      EXPECT_EQ(directed.count({edge.second, edge.first}), 1u) << "an open edge";
    }
    // Pappus: a polygon of `sides` corners on a circle of radius r swept along the
    // centreline: (sides/2) r² sin(2π/sides) × length
    const double r = s.yarn_radius[y];
    const double area = sides / 2.0 * r * r * std::sin(2 * std::numbers::pi / sides);
    EXPECT_NEAR(volume, area * polyline_length(samples[y]), 0.01 * volume);
    for (int v = m.vertex_begin[y]; v < m.vertex_begin[y + 1]; ++v)
      EXPECT_NEAR(m.normals[v].norm(), 1.0, 1e-5);
  }
}

TEST(TubeMesh, RingsLieAtTheRadiusAroundTheCentreline) {
  const StateFile s = two_helices();
  const TubeMesh m = tube_mesh(s, 4, 7);
  const auto samples = sample_yarns(s, 4);
  for (int y = 0; y < 2; ++y)
    for (Eigen::Index k = 0; k < samples[y].cols(); ++k)
      for (int j = 0; j < 7; ++j) {
        const int v = m.vertex_begin[y] + static_cast<int>(k) * 7 + j;
        const Eigen::Vector3d d = m.positions[v].cast<double>() - samples[y].col(k);
        EXPECT_NEAR(d.norm(), s.yarn_radius[y], 1e-5);
        // the ring's plane is across the centreline
        const Eigen::Index a = std::max<Eigen::Index>(k - 1, 0),
                           b = std::min<Eigen::Index>(k + 1, samples[y].cols() - 1);
        const Eigen::Vector3d t = (samples[y].col(b) - samples[y].col(a)).normalized();
        EXPECT_NEAR(d.dot(t), 0, 1e-5);
      }
  EXPECT_THROW(tube_mesh(s, 4, 2), std::invalid_argument);
  EXPECT_THROW(tube_mesh(s, 0, 8), std::invalid_argument);
}

TEST(TubeMesh, BlenderImportsTheObjAndPlyMeshes) {
  KNIT_REQUIRE_READER(blender, "blender", "blender");
  const StateFile s = two_helices();
  const TubeMesh m = tube_mesh(s, 8, 12);
  const auto dir = test::temp_dir("tube-blender");
  const std::string report_faces =
      "objs = sorted((o for o in bpy.data.objects if o.type == 'MESH'), key=lambda o: o.name)\n"
      "with open(sys.argv[-2], 'w') as out:\n"
      "    for o in objs:\n"
      "        vs = [o.matrix_world @ v.co for v in o.data.vertices]\n"
      "        out.write('%s %d %d %.5f %.5f\\n' % (o.name, len(o.data.vertices), "
      "len(o.data.polygons), min(v[2] for v in vs), max(v[2] for v in vs)))\n"
      "sys.exit(0 if objs else 3)\n";
  Eigen::Vector3f lo = m.positions[0], hi = m.positions[0];
  for (const auto& p : m.positions) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const std::string obj = (dir / "tubes.obj").string(), ply = (dir / "tubes.ply").string();
  write_file_atomic(obj, obj_mesh_text(m));
  write_file_atomic(ply, ply_mesh_bytes(m));
  for (const std::string& file : {obj, ply}) {
    SCOPED_TRACE(file);
    const std::string import =
        file == obj
            ? "bpy.ops.wm.obj_import(filepath=sys.argv[-1], forward_axis='Y', up_axis='Z')\n"
            : "bpy.ops.import_mesh.ply(filepath=sys.argv[-1])\n";
    const std::string script =
        "import bpy, sys\nbpy.ops.wm.read_factory_settings(use_empty=True)\n" + import +
        report_faces;
    int rc = 0;
    std::string messages;
    std::istringstream report(test::run_blender(blender, dir, script, file, rc, messages));
    ASSERT_EQ(rc, 0) << messages;
    std::string name;
    long vertices = 0, faces = 0, total_faces = 0;
    double zmin = 1e9, zmax = -1e9, a = 0, b = 0;
    int objects = 0;
    while (report >> name >> vertices >> faces >> a >> b) {
      ++objects;
      total_faces += faces;
      zmin = std::min(zmin, a);
      zmax = std::max(zmax, b);
      // Blender welds nothing: every vertex we wrote is there
      if (file == obj)
        EXPECT_EQ(vertices, m.vertex_begin[objects] - m.vertex_begin[objects - 1]) << name;
    }
    // OBJ: an object per yarn; PLY: one mesh
    EXPECT_EQ(objects, file == obj ? 2 : 1) << messages;
    EXPECT_EQ(total_faces, static_cast<long>(m.triangles.size()));
    EXPECT_NEAR(zmin, lo.z(), 1e-4);
    EXPECT_NEAR(zmax, hi.z(), 1e-4);
  }
}

TEST(TubeMesh, AssimpReadsTheGlbInMetresWithYUp) {
  KNIT_REQUIRE_READER(assimp, "assimp", "assimp-utils");
  const StateFile s = two_helices();
  const TubeMesh m = tube_mesh(s, 8, 12);
  const auto dir = test::temp_dir("tube-assimp");
  const std::string glb = (dir / "tubes.glb").string();
  write_file_atomic(glb, glb_bytes(m));
  std::string out;
  // (run_process keeps stderr: send `assimp info`'s report there)
  ASSERT_EQ(run_process({"/bin/sh", "-c", "exec \"$0\" info \"$1\" 1>&2", assimp, glb}, out), 0)
      << out;
  auto number_after = [&](const std::string& label) {
    const std::regex re(label + ":\\s+([0-9]+)");
    std::smatch match;
    return std::regex_search(out, match, re) ? std::stol(match[1]) : -1L;
  };
  EXPECT_EQ(number_after("Meshes"), 2) << out;
  EXPECT_EQ(number_after("Vertices"), static_cast<long>(m.positions.size())) << out;
  EXPECT_EQ(number_after("Faces"), static_cast<long>(m.triangles.size())) << out;
  // the box: (x, z, −y) / 100 of ours
  Eigen::Vector3f lo = m.positions[0], hi = m.positions[0];
  for (const auto& p : m.positions) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const std::regex box(
      "Minimum point\\s+\\(([-0-9.e]+) ([-0-9.e]+) ([-0-9.e]+)\\)[\\s\\S]*"
      "Maximum point\\s+\\(([-0-9.e]+) ([-0-9.e]+) ([-0-9.e]+)\\)");
  std::smatch b;
  ASSERT_TRUE(std::regex_search(out, b, box)) << out;
  EXPECT_NEAR(std::stod(b[1]), lo.x() / 100, 1e-5);
  EXPECT_NEAR(std::stod(b[2]), lo.z() / 100, 1e-5);
  EXPECT_NEAR(std::stod(b[3]), -hi.y() / 100, 1e-5);
  EXPECT_NEAR(std::stod(b[4]), hi.x() / 100, 1e-5);
  EXPECT_NEAR(std::stod(b[5]), hi.z() / 100, 1e-5);
  EXPECT_NEAR(std::stod(b[6]), -lo.y() / 100, 1e-5);
}

TEST(ExportVtp, VtkReadsTheLinesAndTheirArrays) {
  // Debian's python3, where python3-vtk9 installs VTK (another python3 may come first on
  // the PATH)
  const std::string python = "/usr/bin/python3";
  const StateFile s = two_helices();
  const auto dir = test::temp_dir("vtp-vtk");
  const std::string vtp = (dir / "yarns.vtp").string();
  export_vtp(s, vtp, 8);
  // VTK's own XML reader, as ParaView uses it; prints what it read
  std::ofstream(dir / "read.py")
      << "import sys\n"
         "try:\n"
         "    import vtk\n"
         "except ImportError:\n"
         "    sys.exit(5)\n"
         "sys.stdout = open(sys.argv[2], 'w')\n"
         "r = vtk.vtkXMLPolyDataReader(); r.SetFileName(sys.argv[1]); r.Update()\n"
         "o = r.GetOutput(); pd = o.GetPointData()\n"
         "print('points', o.GetNumberOfPoints(), 'lines', o.GetNumberOfLines(), 'error', "
         "r.GetErrorCode())\n"
         "for k in range(o.GetNumberOfLines()):\n"
         "    print('line', k, o.GetCell(k).GetNumberOfPoints())\n"
         "for name in ['radius', 'yarn', 'row', 'column']:\n"
         "    a = pd.GetArray(name); print(name, a.GetRange()[0], a.GetRange()[1])\n"
         "v = pd.GetArray('velocity'); q = o.GetPoints()\n"
         "print('spin', max(abs(v.GetTuple3(i)[1] + 2 * q.GetPoint(i)[2]) + "
         "abs(v.GetTuple3(i)[2] - 2 * q.GetPoint(i)[1]) + abs(v.GetTuple3(i)[0]) for i in "
         "range(o.GetNumberOfPoints())))\n"
         "print('time', o.GetFieldData().GetArray('TimeValue').GetValue(0))\n";
  std::string messages;
  const std::string report = (dir / "report.txt").string();
  const int rc = run_process({python, (dir / "read.py").string(), vtp, report}, messages);
  const std::string out = slurp(report) + messages;
  if (rc == 5 || !std::filesystem::exists(python)) {
    if (test::readers_skip_requested()) GTEST_SKIP() << "KNIT_SKIP_READERS is set";
    FAIL() << test::reader_missing_message("VTK for Python", "python3-vtk9");
  }
  ASSERT_EQ(rc, 0) << out;
  const auto samples = sample_yarns(s, 8);
  const long n0 = samples[0].cols(), n1 = samples[1].cols();
  std::map<std::string, std::string> got;
  std::istringstream in(out);
  for (std::string line; std::getline(in, line);) {
    const auto space = line.find(' ');
    got[line.substr(0, space)] += line.substr(space + 1) + ";";
  }
  EXPECT_EQ(got["points"], std::to_string(n0 + n1) + " lines 2 error 0;") << out;
  EXPECT_EQ(got["line"], "0 " + std::to_string(n0) + ";1 " + std::to_string(n1) + ";") << out;
  EXPECT_EQ(got["radius"], "0.125 0.125;") << out;
  EXPECT_EQ(got["yarn"], "0.0 1.0;") << out;
  // rows are segment / 8 of 24 segments per helix, over both yarns' 48 segments
  EXPECT_EQ(got["row"], "0.0 5.0;") << out;
  EXPECT_EQ(got["column"], "0.0 7.0;") << out;
  // the velocity is the spline of the control points' rigid spin: ω × y at every sample
  EXPECT_LT(std::stod(got["spin"]), 1e-4) << out;
  EXPECT_EQ(got["time"], "0.25;") << out;
}

}  // namespace
}  // namespace knit
