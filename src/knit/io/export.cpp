#include "knit/io/export.hpp"

#include "knit/util/byte_reader.hpp"

#include <charconv>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "knit/io/bcc.hpp"
#include "knit/io/obj.hpp"
#include "knit/io/states.hpp"
#include "knit/objects/mesh_shape.hpp"
#include "knit/util/atomic_file.hpp"

namespace knit {
namespace {

// shortest round-trip text of a float
void append_float(std::string& out, double value) {
  char buf[32];
  const auto res = std::to_chars(buf, buf + sizeof(buf), static_cast<float>(value));
  out.append(buf, res.ptr);
}

void append_point(std::string& out, const Eigen::Vector3d& p) {
  out += '(';
  append_float(out, p.x());
  out += ", ";
  append_float(out, p.y());
  out += ", ";
  append_float(out, p.z());
  out += ')';
}

void append_points(std::string& out, const Eigen::Matrix3Xd& cp) {
  out += '[';
  for (Eigen::Index k = 0; k < cp.cols(); ++k) {
    if (k) out += ", ";
    append_point(out, cp.col(k));
  }
  out += ']';
}

// the curve's extent: control-point box (it holds the spline) grown by the radius
void append_extent(std::string& out, const Eigen::Matrix3Xd& cp, double radius) {
  const Eigen::Vector3d lo = cp.rowwise().minCoeff().array() - radius;
  const Eigen::Vector3d hi = cp.rowwise().maxCoeff().array() + radius;
  out += '[';
  append_point(out, lo);
  out += ", ";
  append_point(out, hi);
  out += ']';
}

using detail::put;

// a colour per row (or yarn): six hues of wool, in turn
Eigen::Vector3d palette_colour(int key) {
  static const double colours[6][3] = {{0.80, 0.36, 0.25}, {0.88, 0.66, 0.30}, {0.45, 0.62, 0.38},
                                       {0.30, 0.52, 0.72}, {0.55, 0.40, 0.68}, {0.78, 0.45, 0.58}};
  const auto& c = colours[((key % 6) + 6) % 6];
  return {c[0], c[1], c[2]};
}

}  // namespace

namespace {

// one Mesh prim per object, after the yarns (see export.hpp)
void append_objects(std::string& out, const std::vector<StateFile>& frames,
                    const std::vector<double>& times,
                    const std::vector<Eigen::Matrix3Xd>& first_cps,
                    const std::vector<std::shared_ptr<const SceneObject>>& objects) {
  // the region a plane's slab covers: the first state's yarn, grown by its size
  Eigen::AlignedBox3d yarn;
  for (const Eigen::Matrix3Xd& cp : first_cps)
    for (Eigen::Index k = 0; k < cp.cols(); ++k) yarn.extend(Eigen::Vector3d(cp.col(k)));
  Eigen::AlignedBox3d region = yarn;
  region.min() -= yarn.sizes() + Eigen::Vector3d::Constant(1.0);
  region.max() += yarn.sizes() + Eigen::Vector3d::Constant(1.0);
  for (const auto& o : objects) {
    // the surface in the object's frame at the first time; its pose per frame
    const ObjectFrame f0(*o, times.front());
    Eigen::AlignedBox3d local;
    for (int c = 0; c < 8; ++c)
      local.extend(f0.rotation().transpose() *
                   (region.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c)) - f0.origin()));
    const Eigen::AlignedBox3d bounds = local.intersection(o->shape->bounds());
    const double size = bounds.sizes().allFinite() ? bounds.sizes().norm() : local.sizes().norm();
    const TriangleMesh mesh = surface_mesh(*o->shape, local, size / 160);
    // a USD prim name is [A-Za-z0-9_]*
    std::string name = o->name;
    for (char& c : name)
      if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
    out += "    def Mesh \"object_" + name + "\"\n    {\n";
    out += "        uniform bool doubleSided = 0\n";
    out += "        color3f[] primvars:displayColor = [(0.6, 0.65, 0.7)]\n";
    out += "        int[] faceVertexCounts = [";
    for (size_t t = 0; t < mesh.triangles.size(); ++t) out += t ? ", 3" : "3";
    out += "]\n        int[] faceVertexIndices = [";
    for (size_t t = 0; t < mesh.triangles.size(); ++t)
      for (int c = 0; c < 3; ++c) {
        if (t || c) out += ", ";
        out += std::to_string(mesh.triangles[t][c]);
      }
    out += "]\n        point3f[] points = [";
    for (size_t v = 0; v < mesh.vertices.size(); ++v) {
      if (v) out += ", ";
      append_point(out, mesh.vertices[v]);
    }
    out += "]\n        uniform token subdivisionScheme = \"none\"\n";
    auto pose = [&](double time, std::string& translate, std::string& orient) {
      const ObjectFrame f(*o, time);
      translate.clear();
      orient.clear();
      append_point(translate, f.origin());
      const Eigen::Quaterniond q(f.rotation());
      orient = "(";
      append_float(orient, q.w());
      for (double c : {q.x(), q.y(), q.z()}) {
        orient += ", ";
        append_float(orient, c);
      }
      orient += ")";
    };
    std::string tr, ori;
    pose(times.front(), tr, ori);
    out += "        double3 xformOp:translate = " + tr + "\n";
    out += "        quatf xformOp:orient = " + ori + "\n";
    if (o->moving() && frames.size() > 1) {
      std::string trs, oris;
      for (size_t f = 0; f < frames.size(); ++f) {
        pose(times[f], tr, ori);
        trs += "            " + std::to_string(f) + ": " + tr + ",\n";
        oris += "            " + std::to_string(f) + ": " + ori + ",\n";
      }
      out += "        double3 xformOp:translate.timeSamples = {\n" + trs + "        }\n";
      out += "        quatf xformOp:orient.timeSamples = {\n" + oris + "        }\n";
    }
    out += "        uniform token[] xformOpOrder = [\"xformOp:translate\", \"xformOp:orient\"]\n";
    out += "    }\n";
  }
}

}  // namespace

std::string usda_text(const std::vector<StateFile>& frames, const std::vector<double>& times,
                      const std::vector<std::shared_ptr<const SceneObject>>& objects) {
  check_state_sequence(frames, times, "USD export");
  const bool animated = frames.size() > 1;
  double fps = 24;
  if (animated) fps = static_cast<double>(frames.size() - 1) / (times.back() - times.front());
  std::vector<std::vector<Eigen::Matrix3Xd>> cps, vels;
  for (const auto& f : frames) {
    cps.push_back(yarn_control_points(f));
    StateFile v = f;
    v.state.q = f.state.v;
    vels.push_back(yarn_control_points(v));
  }
  std::vector<int> seg_begin;
  for (int n = 0, y = 0; y < static_cast<int>(frames[0].yarn_cp_counts.size()); ++y) {
    seg_begin.push_back(n);
    n += frames[0].yarn_cp_counts[y] - 3;
  }

  std::string out;
  out += "#usda 1.0\n(\n    doc = \"knitsim " KNIT_VERSION
         ": yarn centrelines as exact uniform cubic B-splines (cm)\"\n";
  out += "    defaultPrim = \"Cloth\"\n    metersPerUnit = 0.01\n    upAxis = \"Z\"\n";
  if (animated) {
    out += "    startTimeCode = 0\n    endTimeCode = " + std::to_string(frames.size() - 1) + "\n";
    out += "    timeCodesPerSecond = ";
    append_float(out, fps);
    out += "\n    framesPerSecond = ";
    append_float(out, fps);
    out += "\n";
  }
  out += ")\n\ndef Xform \"Cloth\" (\n    kind = \"component\"\n)\n{\n";
  const StateFile& first = frames.front();
  for (size_t y = 0; y < first.yarn_cp_counts.size(); ++y) {
    const double r = first.yarn_radius[y];
    out += "    def BasisCurves \"yarn_" + std::to_string(y) + "\"\n    {\n";
    out += "        uniform token type = \"cubic\"\n";
    out += "        uniform token basis = \"bspline\"\n";
    out += "        uniform token wrap = \"nonperiodic\"\n";
    out += "        int[] curveVertexCounts = [" + std::to_string(first.yarn_cp_counts[y]) + "]\n";
    const int ncp = first.yarn_cp_counts[y];
    // widths per control point (USD's "vertex" interpolation for cubic curves): 2r
    out += "        float[] widths = [";
    for (int k = 0; k < ncp; ++k) {
      if (k) out += ", ";
      append_float(out, 2 * r);
    }
    out += "] (\n            interpolation = \"vertex\"\n        )\n";
    // colours: by row where the yarn has stitches (each control point takes its segment's
    // row), else one colour per yarn
    out += "        color3f[] primvars:displayColor = [";
    const int seg0 = seg_begin[y], nseg = ncp - 3;
    const bool rows = static_cast<int>(first.stitch.size()) >= seg0 + nseg;
    for (int k = 0; k < (rows ? ncp : 1); ++k) {
      if (k) out += ", ";
      const int key = rows ? first.stitch[seg0 + std::min(k, nseg - 1)].row : static_cast<int>(y);
      append_point(out, palette_colour(key));
    }
    out += "] (\n            interpolation = \"";
    out += rows ? "vertex" : "constant";
    out += "\"\n        )\n";
    out += "        point3f[] points = ";
    append_points(out, cps[0][y]);
    // the control points' velocities (cm/s: USD's velocities are units per second,
    // whatever the time codes), for motion blur
    out += "\n        vector3f[] velocities = ";
    append_points(out, vels[0][y]);
    out += "\n        float3[] extent = ";
    append_extent(out, cps[0][y], r);
    out += "\n";
    if (animated) {
      out += "        point3f[] points.timeSamples = {\n";
      for (size_t f = 0; f < frames.size(); ++f) {
        out += "            " + std::to_string(f) + ": ";
        append_points(out, cps[f][y]);
        out += ",\n";
      }
      out += "        }\n        vector3f[] velocities.timeSamples = {\n";
      for (size_t f = 0; f < frames.size(); ++f) {
        out += "            " + std::to_string(f) + ": ";
        append_points(out, vels[f][y]);
        out += ",\n";
      }
      out += "        }\n        float3[] extent.timeSamples = {\n";
      for (size_t f = 0; f < frames.size(); ++f) {
        out += "            " + std::to_string(f) + ": ";
        append_extent(out, cps[f][y], frames[f].yarn_radius[y]);
        out += ",\n";
      }
      out += "        }\n";
    }
    out += "    }\n";
  }
  append_objects(out, frames, times, cps[0], objects);
  out += "}\n";
  return out;
}

void export_usd(const std::vector<StateFile>& frames, const std::vector<double>& times,
                const std::string& path,
                const std::vector<std::shared_ptr<const SceneObject>>& objects) {
  write_file_atomic(path, usda_text(frames, times, objects));
}

std::string obj_text(const StateFile& state, int per_segment) {
  ObjWriter w("knitsim " KNIT_VERSION ": yarn centrelines as polylines, units cm");
  const auto yarns = sample_yarns(state, per_segment);
  for (size_t y = 0; y < yarns.size(); ++y) {
    w.object("yarn_" + std::to_string(y));
    const Eigen::Matrix3Xd& p = yarns[y];
    for (Eigen::Index k = 0; k < p.cols(); ++k) w.vertex(p.col(k));
    // one two-point line element per span: Blender 3.4's OBJ importer (Debian 12's) keeps
    // only the first span of a longer `l`. Blender makes each object one chain of edges,
    // and our reader joins elements that continue one another back into one yarn.
    for (Eigen::Index k = 0; k + 1 < p.cols(); ++k) w.line(k, k + 1);
  }
  return w.text();
}

void export_obj(const StateFile& state, const std::string& path, int per_segment) {
  write_file_atomic(path, obj_text(state, per_segment));
}

std::string bcc_text(const StateFile& state, int per_segment) {
  return bcc_polylines(sample_yarns(state, per_segment), "knitsim, units cm");
}

void export_bcc(const StateFile& state, const std::string& path, int per_segment) {
  write_file_atomic(path, bcc_text(state, per_segment));
}

std::string ply_bytes(const StateFile& state, bool binary, int per_segment) {
  const auto yarns = sample_yarns(state, per_segment);
  long long nv = 0, ne = 0;
  for (const auto& p : yarns) {
    nv += p.cols();
    ne += p.cols() - 1;
  }
  std::string out = "ply\nformat ";
  out += binary ? "binary_little_endian" : "ascii";
  out += " 1.0\ncomment knitsim " KNIT_VERSION ": yarn centrelines, units cm\n";
  out += "element vertex " + std::to_string(nv) + "\n";
  out += "property float x\nproperty float y\nproperty float z\n";
  out += "property int yarn\nproperty float radius\n";
  out += "element edge " + std::to_string(ne) + "\n";
  out += "property int vertex1\nproperty int vertex2\nend_header\n";
  for (size_t y = 0; y < yarns.size(); ++y) {
    const double r = state.yarn_radius[y];
    for (Eigen::Index k = 0; k < yarns[y].cols(); ++k) {
      if (binary) {
        for (int c = 0; c < 3; ++c) put<float>(out, static_cast<float>(yarns[y](c, k)));
        put<int32_t>(out, static_cast<int32_t>(y));
        put<float>(out, static_cast<float>(r));
      } else {
        for (int c = 0; c < 3; ++c) {
          append_float(out, yarns[y](c, k));
          out += ' ';
        }
        out += std::to_string(y) + ' ';
        append_float(out, r);
        out += '\n';
      }
    }
  }
  long long base = 0;
  for (const auto& p : yarns) {
    for (Eigen::Index k = 0; k + 1 < p.cols(); ++k) {
      const auto a = static_cast<int32_t>(base + k), b = static_cast<int32_t>(base + k + 1);
      if (binary) {
        put<int32_t>(out, a);
        put<int32_t>(out, b);
      } else {
        out += std::to_string(a) + ' ' + std::to_string(b) + '\n';
      }
    }
    base += p.cols();
  }
  return out;
}

void export_ply(const StateFile& state, const std::string& path, bool binary, int per_segment) {
  write_file_atomic(path, ply_bytes(state, binary, per_segment));
}

std::string vtp_text(const StateFile& state, int per_segment) {
  const auto yarns = sample_yarns(state, per_segment);
  // velocities: the same samples of the velocity spline (sampling is linear)
  StateFile velocity = state;
  velocity.state.q = state.state.v;
  const auto speeds = sample_yarns(velocity, per_segment);
  const std::vector<int> cp_begin = state.yarn_cp_begin();
  long long points = 0;
  for (const auto& p : yarns) points += p.cols();
  std::string pos, radius, yarn, row, col, vel, conn, offsets;
  long long next = 0;
  int seg_begin = 0;
  for (size_t y = 0; y < yarns.size(); ++y) {
    const Eigen::Matrix3Xd& p = yarns[y];
    const int nseg = state.yarn_cp_counts[y] - 3;
    for (Eigen::Index k = 0; k < p.cols(); ++k) {
      for (int c = 0; c < 3; ++c) {
        append_float(pos, p(c, k));
        pos += ' ';
        append_float(vel, speeds[y](c, k));
        vel += ' ';
      }
      append_float(radius, state.yarn_radius[y]);
      radius += ' ';
      yarn += std::to_string(y) + ' ';
      // the segment the sample lies on (the last sample ends the last segment)
      const int seg = seg_begin + std::min(static_cast<int>(k / per_segment), nseg - 1);
      const bool known = static_cast<size_t>(seg) < state.stitch.size();
      row += std::to_string(known ? state.stitch[seg].row : -1) + ' ';
      col += std::to_string(known ? state.stitch[seg].col : -1) + ' ';
      conn += std::to_string(next + k) + ' ';
    }
    next += p.cols();
    offsets += std::to_string(next) + ' ';
    seg_begin += nseg;
  }
  std::string out = "<?xml version=\"1.0\"?>\n";
  out += "<!-- knitsim " KNIT_VERSION ": yarn centrelines, units cm -->\n";
  out += "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\">\n";
  out += "<PolyData>\n<FieldData>\n";
  out += "<DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">";
  append_float(out, state.state.time);
  out += "</DataArray>\n</FieldData>\n";
  out += "<Piece NumberOfPoints=\"" + std::to_string(points) +
         "\" NumberOfVerts=\"0\" NumberOfLines=\"" + std::to_string(yarns.size()) +
         "\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">\n";
  out += "<Points>\n<DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">" + pos +
         "</DataArray>\n</Points>\n";
  out += "<PointData Scalars=\"radius\" Vectors=\"velocity\">\n";
  out +=
      "<DataArray type=\"Float32\" Name=\"radius\" format=\"ascii\">" + radius + "</DataArray>\n";
  out += "<DataArray type=\"Int32\" Name=\"yarn\" format=\"ascii\">" + yarn + "</DataArray>\n";
  out += "<DataArray type=\"Int32\" Name=\"row\" format=\"ascii\">" + row + "</DataArray>\n";
  out += "<DataArray type=\"Int32\" Name=\"column\" format=\"ascii\">" + col + "</DataArray>\n";
  out +=
      "<DataArray type=\"Float32\" Name=\"velocity\" NumberOfComponents=\"3\" format=\"ascii\">" +
      vel + "</DataArray>\n";
  out += "</PointData>\n<Lines>\n";
  out +=
      "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">" + conn + "</DataArray>\n";
  out +=
      "<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">" + offsets + "</DataArray>\n";
  out += "</Lines>\n</Piece>\n</PolyData>\n</VTKFile>\n";
  return out;
}

void export_vtp(const StateFile& state, const std::string& path, int per_segment) {
  write_file_atomic(path, vtp_text(state, per_segment));
}

}  // namespace knit
