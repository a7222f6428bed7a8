// Reader for Wavefront OBJ polylines: `v x y z [w]` vertices and `l i j k …` line elements
// (1-based indices, negative ones relative to the vertices read so far, `i/t` accepted).
// A line element that starts at the vertex where the previous one ended continues it, so
// files that write a polyline as many two-point elements still give one yarn. Every other
// statement (faces, groups, normals, materials, comments) is ignored.
#include <charconv>
#include <cmath>

#include "knit/io/import.hpp"

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

std::vector<RawYarn> parse_obj(std::string_view data, const std::string& name) {
  std::vector<Eigen::Vector3d> verts;
  std::vector<std::vector<LineRef>> polylines;
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
                   "vertex needs 3 finite numbers, got '" + std::string(line) + "'");
        p[c] = value;
      }
      verts.push_back(p);
    } else if (key == "l") {
      std::vector<LineRef> refs;
      for (std::string_view tok = next_token(rest); !tok.empty(); tok = next_token(rest)) {
        const std::string_view idx = tok.substr(0, tok.find('/'));
        long long value = 0;
        const auto res = std::from_chars(idx.data(), idx.data() + idx.size(), value);
        if (idx.empty() || res.ec != std::errc() || res.ptr != idx.data() + idx.size() ||
            value == 0)
          obj_fail(name, line_no, line_offset,
                   "bad vertex index '" + std::string(tok) + "' in line element");
        refs.push_back({value, static_cast<long long>(verts.size()), line_no});
      }
      if (refs.size() < 2)
        obj_fail(name, line_no, line_offset, "line element needs at least 2 vertices");
      polylines.push_back(std::move(refs));
    }
  }
  if (polylines.empty())
    throw std::runtime_error(name + ": no polylines ('l' elements) in the OBJ file");

  // resolve indices and join continuing elements
  const long long nv = static_cast<long long>(verts.size());
  std::vector<std::vector<long long>> chains;
  for (const auto& refs : polylines) {
    std::vector<long long> ids;
    for (const LineRef& r : refs) {
      const long long i = r.index > 0 ? r.index - 1 : r.nverts + r.index;
      if (i < 0 || i >= nv)
        throw std::runtime_error(name + ": line " + std::to_string(r.line) + ": vertex index " +
                                 std::to_string(r.index) + " out of range (" + std::to_string(nv) +
                                 " vertices)");
      ids.push_back(i);
    }
    if (!chains.empty() && chains.back().back() == ids.front())
      chains.back().insert(chains.back().end(), ids.begin() + 1, ids.end());
    else
      chains.push_back(std::move(ids));
  }
  std::vector<RawYarn> out;
  for (const auto& ids : chains) {
    RawYarn y;
    y.points.resize(3, static_cast<Eigen::Index>(ids.size()));
    for (size_t k = 0; k < ids.size(); ++k)
      y.points.col(static_cast<Eigen::Index>(k)) = verts[ids[k]];
    out.push_back(std::move(y));
  }
  return out;
}

}  // namespace knit
