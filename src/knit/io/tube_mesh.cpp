#include "knit/io/tube_mesh.hpp"

#include <tiny_gltf.h>

#include <cmath>
#include <cstring>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "knit/io/obj.hpp"
#include "knit/io/states.hpp"
#include "knit/util/byte_reader.hpp"

namespace knit {

namespace {

// any unit vector perpendicular to t
Eigen::Vector3d perpendicular(const Eigen::Vector3d& t) {
  const Eigen::Vector3d a =
      std::abs(t.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  return t.cross(a).normalized();
}

// the tangent at sample k of a polyline (central differences; one-sided at the ends)
Eigen::Vector3d tangent(const Eigen::Matrix3Xd& p, Eigen::Index k, const Eigen::Vector3d& before) {
  const Eigen::Index n = p.cols();
  const Eigen::Vector3d d = p.col(std::min(k + 1, n - 1)) - p.col(std::max<Eigen::Index>(k - 1, 0));
  const double len = d.norm();
  return len > 0 ? Eigen::Vector3d(d / len) : before;
}

}  // namespace

TubeMesh tube_mesh(const StateFile& state, int per_segment, int sides) {
  if (sides < 3) throw std::invalid_argument("tube mesh: sides must be at least 3");
  if (per_segment < 1) throw std::invalid_argument("tube mesh: samples per segment must be >= 1");
  const auto yarns = sample_yarns(state, per_segment);
  TubeMesh m;
  for (size_t y = 0; y < yarns.size(); ++y) {
    m.vertex_begin.push_back(static_cast<int>(m.positions.size()));
    m.triangle_begin.push_back(static_cast<int>(m.triangles.size()));
    const Eigen::Matrix3Xd& p = yarns[y];
    const double r = state.yarn_radius[y];
    const Eigen::Index n = p.cols();
    const int base = static_cast<int>(m.positions.size());
    // rings, their frame carried along by parallel transport (rotating the last normal
    // by the smallest rotation that takes the last tangent to this one)
    Eigen::Vector3d t = tangent(p, 0, Eigen::Vector3d::UnitX());
    Eigen::Vector3d u = perpendicular(t);
    const Eigen::Vector3d t_first = t;
    for (Eigen::Index k = 0; k < n; ++k) {
      const Eigen::Vector3d t_new = tangent(p, k, t);
      u = (u - u.dot(t_new) * t_new);
      u = u.norm() > 1e-12 ? Eigen::Vector3d(u.normalized()) : perpendicular(t_new);
      t = t_new;
      const Eigen::Vector3d w = t.cross(u);
      for (int s = 0; s < sides; ++s) {
        const double a = 2 * std::numbers::pi * s / sides;
        const Eigen::Vector3d dir = std::cos(a) * u + std::sin(a) * w;
        m.positions.push_back((p.col(k) + r * dir).cast<float>());
        m.normals.push_back(dir.cast<float>());
      }
    }
    // quads between rings: with dir = cos·u + sin·w (outward) and τ its derivative around
    // the ring, (u, w, t) is right-handed, so τ × t = dir: a triangle that goes around,
    // then along, turns counter-clockwise seen from outside
    for (Eigen::Index k = 0; k + 1 < n; ++k)
      for (int s = 0; s < sides; ++s) {
        const int a = base + static_cast<int>(k) * sides + s;
        const int b = base + static_cast<int>(k) * sides + (s + 1) % sides;
        const int c = a + sides, d = b + sides;
        m.triangles.emplace_back(a, b, d);
        m.triangles.emplace_back(a, d, c);
      }
    // caps: a centre and a copy of the end ring with the axis as normal
    for (int end = 0; end < 2; ++end) {
      const Eigen::Index k = end == 0 ? 0 : n - 1;
      const Eigen::Vector3d axis = end == 0 ? Eigen::Vector3d(-t_first) : t;
      const int centre = static_cast<int>(m.positions.size());
      m.positions.push_back(p.col(k).cast<float>());
      m.normals.push_back(axis.cast<float>());
      const int ring = base + static_cast<int>(k) * sides;
      for (int s = 0; s < sides; ++s) {
        m.positions.push_back(m.positions[static_cast<size_t>(ring + s)]);
        m.normals.push_back(axis.cast<float>());
      }
      for (int s = 0; s < sides; ++s) {
        const int a = centre + 1 + s, b = centre + 1 + (s + 1) % sides;
        // the start cap faces −t: its ring turns clockwise seen from outside
        if (end == 0)
          m.triangles.emplace_back(centre, b, a);
        else
          m.triangles.emplace_back(centre, a, b);
      }
    }
  }
  m.vertex_begin.push_back(static_cast<int>(m.positions.size()));
  m.triangle_begin.push_back(static_cast<int>(m.triangles.size()));
  return m;
}

std::string obj_mesh_text(const TubeMesh& m) {
  ObjWriter w("knitsim " KNIT_VERSION ": yarn tubes (triangles with normals), units cm, Z up");
  for (int y = 0; y < m.num_yarns(); ++y) {
    w.object("yarn_" + std::to_string(y));
    const int v0 = m.vertex_begin[y];
    for (int v = v0; v < m.vertex_begin[y + 1]; ++v) w.vertex(m.positions[v].cast<double>());
    for (int v = v0; v < m.vertex_begin[y + 1]; ++v) w.normal(m.normals[v].cast<double>());
    for (int t = m.triangle_begin[y]; t < m.triangle_begin[y + 1]; ++t)
      w.triangle(m.triangles[t][0] - v0, m.triangles[t][1] - v0, m.triangles[t][2] - v0);
  }
  return w.text();
}

std::string ply_mesh_bytes(const TubeMesh& m) {
  std::string out = "ply\nformat binary_little_endian 1.0\n";
  out += "comment knitsim " KNIT_VERSION ": yarn tubes, units cm, Z up\n";
  out += "element vertex " + std::to_string(m.positions.size()) + "\n";
  out += "property float x\nproperty float y\nproperty float z\n";
  out += "property float nx\nproperty float ny\nproperty float nz\nproperty int yarn\n";
  out += "element face " + std::to_string(m.triangles.size()) + "\n";
  out += "property list uchar int vertex_indices\nend_header\n";
  for (int y = 0; y < m.num_yarns(); ++y)
    for (int v = m.vertex_begin[y]; v < m.vertex_begin[y + 1]; ++v) {
      for (int c = 0; c < 3; ++c) detail::put<float>(out, m.positions[v][c]);
      for (int c = 0; c < 3; ++c) detail::put<float>(out, m.normals[v][c]);
      detail::put<int32_t>(out, y);
    }
  for (const Eigen::Vector3i& t : m.triangles) {
    detail::put<uint8_t>(out, 3);
    for (int c = 0; c < 3; ++c) detail::put<int32_t>(out, t[c]);
  }
  return out;
}

std::string glb_bytes(const TubeMesh& m) {
  // glTF: metres, +Y up, right-handed: (x, y, z) cm, Z up → (x, z, −y) / 100 m
  auto to_gltf = [](const Eigen::Vector3f& p, float scale) {
    return Eigen::Vector3f(p.x() * scale, p.z() * scale, -p.y() * scale);
  };
  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = "knitsim " KNIT_VERSION;
  tinygltf::Buffer buffer;
  tinygltf::Scene scene;
  tinygltf::Material material;
  material.name = "yarn";
  material.pbrMetallicRoughness.baseColorFactor = {0.8, 0.45, 0.3, 1.0};
  material.pbrMetallicRoughness.metallicFactor = 0.0;
  material.pbrMetallicRoughness.roughnessFactor = 0.9;
  model.materials.push_back(material);
  auto append = [&](const void* data, size_t bytes) {
    const size_t offset = buffer.data.size();
    const auto* b = static_cast<const unsigned char*>(data);
    buffer.data.insert(buffer.data.end(), b, b + bytes);
    while (buffer.data.size() % 4) buffer.data.push_back(0);
    return offset;
  };
  auto add_view = [&](size_t offset, size_t bytes, int target) {
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = offset;
    view.byteLength = bytes;
    view.target = target;
    model.bufferViews.push_back(view);
    return static_cast<int>(model.bufferViews.size()) - 1;
  };
  for (int y = 0; y < m.num_yarns(); ++y) {
    const int v0 = m.vertex_begin[y], v1 = m.vertex_begin[y + 1];
    std::vector<float> pos, nrm;
    std::vector<double> lo(3, 1e300), hi(3, -1e300);
    for (int v = v0; v < v1; ++v) {
      const Eigen::Vector3f p = to_gltf(m.positions[v], 0.01f), n = to_gltf(m.normals[v], 1.0f);
      for (int c = 0; c < 3; ++c) {
        pos.push_back(p[c]);
        nrm.push_back(n[c]);
        lo[c] = std::min(lo[c], static_cast<double>(p[c]));
        hi[c] = std::max(hi[c], static_cast<double>(p[c]));
      }
    }
    std::vector<uint32_t> idx;
    for (int t = m.triangle_begin[y]; t < m.triangle_begin[y + 1]; ++t)
      for (int c = 0; c < 3; ++c) idx.push_back(static_cast<uint32_t>(m.triangles[t][c] - v0));
    const int pv =
        add_view(append(pos.data(), pos.size() * 4), pos.size() * 4, TINYGLTF_TARGET_ARRAY_BUFFER);
    const int nv =
        add_view(append(nrm.data(), nrm.size() * 4), nrm.size() * 4, TINYGLTF_TARGET_ARRAY_BUFFER);
    const int iv = add_view(append(idx.data(), idx.size() * 4), idx.size() * 4,
                            TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
    auto accessor = [&](int view, int component, int type, size_t count) {
      tinygltf::Accessor a;
      a.bufferView = view;
      a.componentType = component;
      a.type = type;
      a.count = count;
      model.accessors.push_back(a);
      return static_cast<int>(model.accessors.size()) - 1;
    };
    const int pa = accessor(pv, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3,
                            static_cast<size_t>(v1 - v0));
    model.accessors[pa].minValues = lo;
    model.accessors[pa].maxValues = hi;
    const int na = accessor(nv, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3,
                            static_cast<size_t>(v1 - v0));
    const int ia =
        accessor(iv, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, TINYGLTF_TYPE_SCALAR, idx.size());
    tinygltf::Primitive prim;
    prim.attributes["POSITION"] = pa;
    prim.attributes["NORMAL"] = na;
    prim.indices = ia;
    prim.material = 0;
    prim.mode = TINYGLTF_MODE_TRIANGLES;
    tinygltf::Mesh mesh;
    mesh.name = "yarn_" + std::to_string(y);
    mesh.primitives.push_back(prim);
    model.meshes.push_back(mesh);
    tinygltf::Node node;
    node.name = mesh.name;
    node.mesh = static_cast<int>(model.meshes.size()) - 1;
    model.nodes.push_back(node);
    scene.nodes.push_back(static_cast<int>(model.nodes.size()) - 1);
  }
  model.buffers.push_back(buffer);
  model.scenes.push_back(scene);
  model.defaultScene = 0;
  std::ostringstream out;
  tinygltf::TinyGLTF writer;
  if (!writer.WriteGltfSceneToStream(&model, out, false, true))
    throw std::runtime_error("glTF export: tinygltf could not write the model");
  return out.str();
}

}  // namespace knit
