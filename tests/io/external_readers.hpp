#pragma once
// Real readers of our exports, run by the tests: Blender (OBJ, PLY), Assimp (glTF) and VTK
// (VTP). scripts/test.sh installs them (Debian's blender, assimp-utils, python3-vtk9), so
// these tests run wherever the suite does; without a reader they fail, unless
// KNIT_SKIP_READERS=1 (or KNIT_SKIP_BLENDER=1) asks to skip them.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "knit/util/process.hpp"

namespace knit::test {

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline bool readers_skip_requested() {
  for (const char* name : {"KNIT_SKIP_READERS", "KNIT_SKIP_BLENDER"}) {
    const char* v = std::getenv(name);
    if (v != nullptr && std::strcmp(v, "") != 0 && std::strcmp(v, "0") != 0) return true;
  }
  return false;
}

inline std::string reader_missing_message(const std::string& reader, const std::string& package) {
  return reader + " is not installed (scripts/test.sh installs Debian's " + package +
         "; set KNIT_SKIP_READERS=1 to skip the tests that need it)";
}

/// The path of `program`, or skips the test (KNIT_SKIP_READERS) or fails it naming the
/// package that provides it.
#define KNIT_REQUIRE_READER(var, program, package)                                          \
  const std::string var = ::knit::find_executable(program);                                 \
  if (var.empty()) {                                                                        \
    if (::knit::test::readers_skip_requested()) GTEST_SKIP() << "KNIT_SKIP_READERS is set"; \
    FAIL() << ::knit::test::reader_missing_message(program, package);                       \
  }

// Runs `script` (Python) in a headless Blender with `file` as its last argument; the script
// writes what it found to the file named by its second-to-last argument, returned here.
// Blender's exit status goes to `rc`, its messages to `messages`.
inline std::string run_blender(const std::string& blender, const std::filesystem::path& dir,
                               const std::string& script, const std::string& file, int& rc,
                               std::string& messages) {
  std::ofstream(dir / "check.py") << script;
  const std::string report = (dir / "report.txt").string();
  rc = run_process({blender, "-b", "--factory-startup", "--python", (dir / "check.py").string(),
                    "--", report, file},
                   messages);
  return slurp(report);
}

// One line per mesh object, sorted by name: "name vertices edges min_x min_y min_z max_x
// max_y max_z" (cm, as in the file: the importers are told not to turn the axes).
inline const char* const BLENDER_MESH_REPORT =
    "objs = sorted((o for o in bpy.data.objects if o.type == 'MESH'), key=lambda o: o.name)\n"
    "with open(sys.argv[-2], 'w') as out:\n"
    "    for o in objs:\n"
    "        vs = [o.matrix_world @ v.co for v in o.data.vertices]\n"
    "        lo = [min(v[i] for v in vs) for i in range(3)]\n"
    "        hi = [max(v[i] for v in vs) for i in range(3)]\n"
    "        out.write('%s %d %d %.6f %.6f %.6f %.6f %.6f %.6f\\n' % ((o.name, "
    "len(o.data.vertices),\n"
    "                  len(o.data.edges)) + tuple(lo) + tuple(hi)))\n"
    "sys.exit(0 if objs else 3)\n";

struct MeshReport {
  std::string name;
  long vertices = 0, edges = 0;
  Eigen::Vector3d lo, hi;
};

inline std::vector<MeshReport> parse_mesh_report(const std::string& text) {
  std::vector<MeshReport> out;
  std::istringstream in(text);
  MeshReport m;
  while (in >> m.name >> m.vertices >> m.edges >> m.lo.x() >> m.lo.y() >> m.lo.z() >> m.hi.x() >>
         m.hi.y() >> m.hi.z())
    out.push_back(m);
  return out;
}

}  // namespace knit::test
