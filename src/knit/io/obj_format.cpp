// Wavefront OBJ (obj.hpp): one parser for yarn polylines and object meshes. For yarns, a
// line element that starts at the vertex where the previous one ended continues it, so
// files that write a polyline as many two-point elements still give one yarn.
#include <charconv>
#include <cmath>
#include <sstream>

#include "knit/io/import.hpp"
#include "knit/io/obj.hpp"
#include "knit/util/atomic_file.hpp"
#include "knit/util/input_file.hpp"

namespace knit {
namespace {

struct LineRef {
  long long index;   // as written
  long long nverts;  // vertices defined before this statement (for negative indices)
  size_t line;       // 1-based line number
};

[[noreturn]] void obj_fail(const std::string& name, size_t line, size_t offset,
                           const std::string& msg) {
  throw std::runtime_error(name + ": line " + std::to_string(line) + " (byte " +
                           std::to_string(offset) + "): " + msg);
}

std::string_view next_token(std::string_view& s) {
  size_t b = s.find_first_not_of(" \t\r");
  if (b == std::string_view::npos) {
    s = {};
    return {};
  }
  size_t e = s.find_first_of(" \t\r", b);
  if (e == std::string_view::npos) e = s.size();
  std::string_view tok = s.substr(b, e - b);
  s.remove_prefix(e);
  return tok;
}

}  // namespace

ObjGeometry parse_obj_geometry(std::string_view data, const std::string& name) {
  ObjGeometry g;
  // indices as written, resolved once every vertex is read (a positive index may point
  // ahead); each element with the line it came from
  std::vector<std::vector<LineRef>> lines, faces;
  size_t line_no = 0, pos = 0;
  while (pos < data.size()) {
    size_t end = data.find('\n', pos);
    if (end == std::string_view::npos) end = data.size();
    std::string_view line = data.substr(pos, end - pos);
    const size_t line_offset = pos;
    pos = end + 1;
    ++line_no;
    const size_t hash = line.find('#');
    if (hash != std::string_view::npos) line = line.substr(0, hash);
    std::string_view rest = line;
    const std::string_view key = next_token(rest);
    if (key == "v") {
      Eigen::Vector3d p;
      for (int c = 0; c < 3; ++c) {
        const std::string_view tok = next_token(rest);
        double value = 0;
        const auto res = std::from_chars(tok.data(), tok.data() + tok.size(), value);
        if (tok.empty() || res.ec != std::errc() || res.ptr != tok.data() + tok.size() ||
            !std::isfinite(value))
          obj_fail(name, line_no, line_offset,
                   "vertex needs 3 finite numbers, got '" + printable(line, 80) + "'");
        p[c] = value;
      }
      g.vertices.push_back(p);
    } else if (key == "l" || key == "f") {
      const bool face = key == "f";
      std::vector<LineRef> refs;
      for (std::string_view tok = next_token(rest); !tok.empty(); tok = next_token(rest)) {
        const std::string_view idx = tok.substr(0, tok.find('/'));
        long long value = 0;
        const auto res = std::from_chars(idx.data(), idx.data() + idx.size(), value);
        if (idx.empty() || res.ec != std::errc() || res.ptr != idx.data() + idx.size() ||
            value == 0)
          obj_fail(name, line_no, line_offset,
                   "bad vertex index '" + printable(tok, 40) + "' in " +
                       (face ? "face" : "line element"));
        refs.push_back({value, static_cast<long long>(g.vertices.size()), line_no});
      }
      if (!face && refs.size() < 2)
        obj_fail(name, line_no, line_offset, "line element needs at least 2 vertices");
      if (face && refs.size() < 3)
        obj_fail(name, line_no, line_offset, "a face needs at least three corners");
      (face ? faces : lines).push_back(std::move(refs));
    }
  }
  const long long nv = static_cast<long long>(g.vertices.size());
  auto resolve = [&](const std::vector<LineRef>& refs) {
    std::vector<long long> ids;
    for (const LineRef& r : refs) {
      const long long i = r.index > 0 ? r.index - 1 : r.nverts + r.index;
      if (i < 0 || i >= nv)
        throw std::runtime_error(name + ": line " + std::to_string(r.line) + ": vertex index " +
                                 std::to_string(r.index) + " out of range (" + std::to_string(nv) +
                                 " vertices)");
      ids.push_back(i);
    }
    return ids;
  };
  for (const auto& refs : lines) g.lines.push_back(resolve(refs));
  for (const auto& refs : faces) g.faces.push_back(resolve(refs));
  return g;
}

std::vector<RawYarn> parse_obj(std::string_view data, const std::string& name) {
  const ObjGeometry g = parse_obj_geometry(data, name);
  if (g.lines.empty())
    throw std::runtime_error(name + ": no polylines ('l' elements) in the OBJ file");
  // an element that starts where the previous one ended continues it
  std::vector<std::vector<long long>> chains;
  for (const std::vector<long long>& ids : g.lines) {
    if (!chains.empty() && chains.back().back() == ids.front())
      chains.back().insert(chains.back().end(), ids.begin() + 1, ids.end());
    else
      chains.push_back(ids);
  }
  std::vector<RawYarn> out;
  for (const auto& ids : chains) {
    RawYarn y;
    y.points.resize(3, static_cast<Eigen::Index>(ids.size()));
    for (size_t k = 0; k < ids.size(); ++k)
      y.points.col(static_cast<Eigen::Index>(k)) = g.vertices[ids[k]];
    out.push_back(std::move(y));
  }
  return out;
}

TriangleMesh read_obj_mesh(const std::string& path, double scale) {
  const ObjGeometry g = parse_obj_geometry(read_input_file(path, MAX_GEOMETRY_BYTES, "mesh"), path);
  if (g.faces.empty()) throw std::runtime_error(path + ": the mesh has no faces ('f' statements)");
  TriangleMesh mesh;
  for (const Eigen::Vector3d& v : g.vertices) mesh.vertices.push_back(scale * v);
  for (const std::vector<long long>& f : g.faces)
    for (size_t k = 1; k + 1 < f.size(); ++k)
      mesh.triangles.emplace_back(static_cast<int>(f[0]), static_cast<int>(f[k]),
                                  static_cast<int>(f[k + 1]));
  return mesh;
}

ObjWriter::ObjWriter(std::string_view header) {
  m_out = "# ";
  m_out += header;
  m_out += '\n';
}

void ObjWriter::object(std::string_view name) {
  if (!name.empty()) {
    m_out += "o ";
    m_out += name;
    m_out += '\n';
  }
  m_vertex_base = m_vertices;
  m_normal_base = m_normals;
}

void ObjWriter::append(const Eigen::Vector3d& p) {
  for (int c = 0; c < 3; ++c) {
    char buf[32];
    const auto res = std::to_chars(buf, buf + sizeof buf, static_cast<float>(p[c]));
    m_out += ' ';
    m_out.append(buf, res.ptr);
  }
  m_out += '\n';
}

void ObjWriter::vertex(const Eigen::Vector3d& p) {
  m_out += 'v';
  append(p);
  ++m_vertices;
}

void ObjWriter::normal(const Eigen::Vector3d& n) {
  m_out += "vn";
  append(n);
  ++m_normals;
}

void ObjWriter::line(long long a, long long b) {
  m_out += "l " + std::to_string(m_vertex_base + a + 1) + ' ' +
           std::to_string(m_vertex_base + b + 1) + '\n';
}

void ObjWriter::triangle(long long a, long long b, long long c) {
  const bool normals = m_normals > m_normal_base;
  m_out += 'f';
  for (long long v : {a, b, c}) {
    const std::string i = std::to_string(m_vertex_base + v + 1);
    m_out += ' ' + i;
    if (normals) m_out += "//" + std::to_string(m_normal_base + v + 1);
  }
  m_out += '\n';
}

void write_obj_mesh(const TriangleMesh& mesh, const std::string& path) {
  ObjWriter w("knitsim object surface (cm)");
  w.object("");
  for (const Eigen::Vector3d& v : mesh.vertices) w.vertex(v);
  for (const Eigen::Vector3i& t : mesh.triangles) w.triangle(t[0], t[1], t[2]);
  write_file_atomic(path, w.text());
}

}  // namespace knit
