#include "knit/io/state_file.hpp"

#include "knit/io/byte_reader.hpp"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace knit {
namespace {

constexpr char MAGIC[8] = {'K', 'N', 'I', 'T', 'S', 'T', 'A', 'T'};
constexpr char END_MAGIC[4] = {'K', 'E', 'N', 'D'};

using detail::put;

}  // namespace

int StateFile::num_cp() const {
  int n = 0;
  for (int c : yarn_cp_counts) n += c;
  return n;
}

int StateFile::num_seg() const {
  int n = 0;
  for (int c : yarn_cp_counts) n += c - 3;
  return n;
}

std::vector<int> StateFile::yarn_cp_begin() const {
  std::vector<int> begin;
  int c = 0;
  for (int n : yarn_cp_counts) {
    begin.push_back(c);
    c += n;
  }
  return begin;
}

StateFile make_state_file(const Model& model, const State& state) {
  StateFile f;
  f.state = state;
  for (const YarnInfo& y : model.yarns) {
    f.yarn_cp_counts.push_back(y.num_cp());
    f.yarn_radius.push_back(model.params.radius);
  }
  if (model.has_stitches()) f.stitch = model.stitch;
  return f;
}

void write_file_atomic(const std::string& path, const std::string& contents) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  const fs::path tmp = target.parent_path() / (target.filename().string() + ".tmp");
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error(path + ": cannot open for writing");
    out.write(contents.data(), static_cast<std::streamsize>(contents.size()));
    out.flush();
    if (!out) {
      out.close();
      fs::remove(tmp);
      throw std::runtime_error(path + ": write failed (disk full?)");
    }
  }
  std::error_code ec;
  fs::rename(tmp, target, ec);
  if (ec) {
    fs::remove(tmp);
    throw std::runtime_error(path + ": cannot rename temporary file: " + ec.message());
  }
}

void write_state_file(const std::string& path, const StateFile& f) {
  const int ncp = f.num_cp();
  if (f.state.q.size() != 3 * ncp || f.state.v.size() != 3 * ncp)
    throw std::invalid_argument(path + ": state size does not match the yarn layout");
  std::string out;
  out.reserve(64 + 48 * ncp);
  out.append(MAGIC, 8);
  put<uint32_t>(out, STATE_FILE_VERSION);
  put<uint32_t>(out, static_cast<uint32_t>(f.yarn_cp_counts.size()));
  put<uint32_t>(out, f.stitch.empty() ? 0u : 1u);
  put<double>(out, f.state.time);
  for (size_t y = 0; y < f.yarn_cp_counts.size(); ++y) {
    put<uint32_t>(out, static_cast<uint32_t>(f.yarn_cp_counts[y]));
    put<double>(out, f.yarn_radius[y]);
  }
  for (int k = 0; k < 3 * ncp; ++k) put<double>(out, f.state.q[k]);
  for (int k = 0; k < 3 * ncp; ++k) put<double>(out, f.state.v[k]);
  if (!f.stitch.empty()) {
    if (static_cast<int>(f.stitch.size()) != f.num_seg())
      throw std::invalid_argument(path + ": stitch coordinates do not match the segments");
    for (const StitchCoord& s : f.stitch) {
      put<int32_t>(out, s.row);
      put<int32_t>(out, s.col);
    }
  }
  out.append(END_MAGIC, 4);
  write_file_atomic(path, out);
}

StateFile read_state_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open state file");
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string data = ss.str();
  detail::ByteReader r(data, path);
  if (r.bytes(8, "magic") != std::string_view(MAGIC, 8))
    r.fail_at(0, "not a knitsim state file (bad magic)");
  const auto version = r.get<uint32_t>("version");
  if (version != STATE_FILE_VERSION)
    r.fail("unsupported state file version " + std::to_string(version) + " (this build reads " +
           std::to_string(STATE_FILE_VERSION) + ")");
  const auto nyarn = r.get<uint32_t>("yarn count");
  const auto flags = r.get<uint32_t>("flags");
  if (flags > 1) r.fail("unknown flags " + std::to_string(flags));
  StateFile f;
  f.state.time = r.get<double>("time");
  if (nyarn == 0 || nyarn > r.remaining() / 12)
    r.fail("implausible yarn count " + std::to_string(nyarn));
  long long total = 0;
  for (uint32_t y = 0; y < nyarn; ++y) {
    const auto n = r.get<uint32_t>("yarn control point count");
    if (n < 4)
      r.fail("yarn " + std::to_string(y) + " has " + std::to_string(n) +
             " control points (need >= 4)");
    const double radius = r.get<double>("yarn radius");
    if (!(radius > 0) || !std::isfinite(radius))
      r.fail("yarn " + std::to_string(y) + " has a bad radius");
    total += n;
    if (total * 48 > static_cast<long long>(r.remaining()))
      r.fail("control point counts exceed the file size");
    f.yarn_cp_counts.push_back(static_cast<int>(n));
    f.yarn_radius.push_back(radius);
  }
  f.state.q.resize(3 * total);
  f.state.v.resize(3 * total);
  for (long long k = 0; k < 3 * total; ++k) f.state.q[k] = r.get<double>("positions");
  for (long long k = 0; k < 3 * total; ++k) f.state.v[k] = r.get<double>("velocities");
  if (flags & 1u) {
    f.stitch.resize(f.num_seg());
    for (auto& s : f.stitch) {
      s.row = r.get<int32_t>("stitch row");
      s.col = r.get<int32_t>("stitch column");
    }
  }
  if (r.bytes(4, "end marker") != std::string_view(END_MAGIC, 4)) r.fail("bad end marker");
  if (r.remaining() != 0) r.fail("unexpected bytes after the end marker");
  return f;
}

}  // namespace knit
