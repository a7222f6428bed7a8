#include "knit/io/state_file.hpp"

#include "knit/util/atomic_file.hpp"
#include "knit/util/byte_reader.hpp"
#include "knit/util/input_file.hpp"
#include "knit/util/run_dir.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include <zlib.h>

namespace knit {
namespace {

constexpr char MAGIC[8] = {'K', 'N', 'I', 'T', 'S', 'T', 'A', 'T'};
constexpr char END_MAGIC[4] = {'K', 'E', 'N', 'D'};

using detail::put;

// CRC-32 (zlib) of everything before the checksum field
uint32_t checksum(std::string_view bytes) {
  uLong crc = crc32(0L, Z_NULL, 0);
  // zlib takes lengths as uInt: feed it in chunks
  constexpr size_t CHUNK = 1u << 30;
  for (size_t pos = 0; pos < bytes.size(); pos += CHUNK) {
    const size_t n = std::min(CHUNK, bytes.size() - pos);
    crc = crc32(crc, reinterpret_cast<const Bytef*>(bytes.data() + pos), static_cast<uInt>(n));
  }
  return static_cast<uint32_t>(crc);
}

std::string join_names(const std::vector<std::string>& names) {
  std::string text;
  for (size_t k = 0; k < names.size(); ++k)
    text += (k == 0 ? "" : k + 1 == names.size() ? " or " : ", ") + ("\"" + names[k] + "\"");
  return text;
}

// the settings a relaxation wrote, each within the range its option takes; throws
// std::invalid_argument naming the key
KnitRelaxSettings parse_relaxation(const nlohmann::json& j) {
  if (!j.is_object()) throw std::invalid_argument("relaxation: not a JSON object");
  auto value = [&](const char* key) -> const nlohmann::json& {
    if (!j.contains(key))
      throw std::invalid_argument(std::string("relaxation.") + key + ": missing");
    return j.at(key);
  };
  auto fail = [](const char* key, const std::string& what) {
    throw std::invalid_argument(std::string("relaxation.") + key + ": " + what);
  };
  auto boolean = [&](const char* key) {
    if (!value(key).is_boolean()) fail(key, "not true or false");
    return value(key).get<bool>();
  };
  auto number = [&](const char* key) {
    if (!value(key).is_number() || !std::isfinite(value(key).get<double>()))
      fail(key, "not a finite number");
    return value(key).get<double>();
  };
  auto param = [&](const char* key, double v) {  // within the parameter's range (params.hpp)
    try {
      check_param(key, v);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string("relaxation.") + e.what());
    }
    return v;
  };
  auto integer_param = [&](const char* key) {
    if (!value(key).is_number_integer()) fail(key, "not an integer");
    return static_cast<int>(param(key, static_cast<double>(value(key).get<long long>())));
  };
  auto at_least = [&](const char* key, double min, bool strict) {
    const double v = number(key);
    if (strict ? !(v > min) : !(v >= min))
      fail(key, short_number(v) + " is " + (strict ? "not above " : "below ") + short_number(min));
    return v;
  };
  KnitRelaxSettings s;
  s.fire = boolean("fire");
  for (const std::string& name : relax_setting_params()) {
    const ParamDecl& d = param_decl(name);
    const char* key = d.name;
    switch (d.type) {
      case ParamType::BOOLEAN:
        d.set(s.params, boolean(key) ? 1 : 0);
        break;
      case ParamType::CHOICE: {
        if (!value(key).is_string()) fail(key, "not a string");
        const std::vector<std::string>& names = d.choices();
        const auto it = std::find(names.begin(), names.end(), value(key).get<std::string>());
        if (it == names.end()) fail(key, "not one of " + join_names(names));
        d.set(s.params, static_cast<double>(it - names.begin()));
        break;
      }
      case ParamType::INTEGER:
        d.set(s.params, integer_param(key));
        break;
      case ParamType::REAL:
        d.set(s.params, param(key, number(key)));
        break;
    }
  }
  s.ke_per_length = at_least("ke_per_length", 0, true);
  s.force_residual = at_least("force_residual", 0, false);
  if (!value("check_every").is_number_integer()) fail("check_every", "not an integer");
  const long long every = value("check_every").get<long long>();
  if (every < 1 || every > 1'000'000'000)
    fail("check_every", std::to_string(every) + " is outside 1 to 1000000000 steps");
  s.check_every = static_cast<int>(every);
  s.contact_reuse_widen = at_least("contact_reuse_widen", 1, false);
  s.contact_reuse_widen_residual = at_least("contact_reuse_widen_residual", 0, true);
  return s;
}

}  // namespace

nlohmann::json to_json(const KnitRelaxSettings& s) {
  nlohmann::json j = {{"fire", s.fire},
                      {"ke_per_length", s.ke_per_length},
                      {"force_residual", s.force_residual},
                      {"check_every", s.check_every},
                      {"contact_reuse_widen", s.contact_reuse_widen},
                      {"contact_reuse_widen_residual", s.contact_reuse_widen_residual}};
  for (const std::string& name : relax_setting_params())
    j[name] = param_json(param_decl(name), s.params);
  return j;
}

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
    f.yarn_radius.push_back(model.params.material.radius);
  }
  if (model.has_stitches()) f.stitch = model.stitch;
  if (model.knit) {
    f.knit = model.knit;
    f.rest_length = model.rest_length;
    f.glues = model.glues;
  }
  return f;
}

void write_state_file(const std::string& path, const StateFile& f) {
  const int ncp = f.num_cp();
  if (f.state.q.size() != 3 * ncp || f.state.v.size() != 3 * ncp)
    throw std::invalid_argument(path + ": state size does not match the yarn layout");
  std::string out;
  out.reserve(64 + 48 * ncp);
  out.append(MAGIC, 8);
  // (version 3 where the file has nothing of version 4's: earlier builds read it too)
  put<uint32_t>(out, f.run ? STATE_FILE_VERSION : 3u);
  put<uint32_t>(out, static_cast<uint32_t>(f.yarn_cp_counts.size()));
  put<uint32_t>(out, (f.stitch.empty() ? 0u : 1u) | (f.knit ? 2u : 0u) | (f.run ? 4u : 0u));
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
  if (f.knit) {
    if (static_cast<int>(f.rest_length.size()) != f.num_seg())
      throw std::invalid_argument(path + ": rest lengths do not match the segments");
    nlohmann::json knit = {{"pattern", f.knit->pattern},
                           {"rows", f.knit->rows},
                           {"cols", f.knit->cols},
                           {"in_the_round", f.knit->in_the_round},
                           {"segments_per_stitch", f.knit->segments_per_stitch},
                           {"stitch_size_cm", f.knit->stitch_size_cm},
                           {"shrink", f.knit->shrink},
                           {"bind_off", f.knit->bind_off},
                           {"cast_on", f.knit->cast_on}};
    if (f.knit->relaxation) knit["relaxation"] = to_json(*f.knit->relaxation);
    const std::string info = knit.dump();
    put<uint32_t>(out, static_cast<uint32_t>(info.size()));
    out.append(info);
    for (double l : f.rest_length) put<double>(out, l);
    put<uint32_t>(out, static_cast<uint32_t>(f.glues.size()));
    for (const Glue& g : f.glues) {
      put<int32_t>(out, g.a.segment);
      put<double>(out, g.a.t);
      put<int32_t>(out, g.b.segment);
      put<double>(out, g.b.t);
      for (int c = 0; c < 3; ++c) put<double>(out, g.gap[c]);
      put<double>(out, g.close_time);
    }
  }
  if (f.run) {
    const std::string run = to_json(*f.run).dump();
    put<uint32_t>(out, static_cast<uint32_t>(run.size()));
    out.append(run);
  }
  out.append(END_MAGIC, 4);
  put<uint32_t>(out, checksum(out));
  write_file_atomic(path, out);
}

StateFile read_state_file(const std::string& path) {
  const std::string data = read_input_file(path, MAX_STATE_BYTES, "state file");
  detail::ByteReader r(data, path);
  if (r.bytes(8, "magic") != std::string_view(MAGIC, 8))
    r.fail_at(0, "not a knitsim state file (bad magic)");
  const auto version = r.get<uint32_t>("version");
  if (version < 1 || version > STATE_FILE_VERSION)
    r.fail("unsupported state file version " + std::to_string(version) +
           " (this build reads 1 to " + std::to_string(STATE_FILE_VERSION) + ")");
  if (version >= 3) {
    // the whole file is checked before any of it is believed
    if (data.size() < 4 + 24) r.fail_at(data.size(), "file too short for its checksum");
    uint32_t stored;
    std::memcpy(&stored, data.data() + data.size() - 4, 4);
    if (stored != checksum(std::string_view(data).substr(0, data.size() - 4)))
      r.fail_at(data.size() - 4,
                "checksum mismatch: the file is corrupted (changed after it was written)");
  }
  const auto nyarn = r.get<uint32_t>("yarn count");
  const auto flags = r.get<uint32_t>("flags");
  if (flags > (version >= 4 ? 7u : version >= 2 ? 3u : 1u))
    r.fail("unknown flags " + std::to_string(flags));
  StateFile f;
  f.state.time = r.get<double>("time");
  if (!std::isfinite(f.state.time) || f.state.time < 0)
    r.fail("the time is " + std::to_string(f.state.time) + " s (expected a finite time >= 0)");
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
  for (long long k = 0; k < 3 * total; ++k) {
    f.state.q[k] = r.get<double>("positions");
    if (!std::isfinite(f.state.q[k]))
      r.fail("control point " + std::to_string(k / 3) + " has a position that is not finite");
  }
  for (long long k = 0; k < 3 * total; ++k) {
    f.state.v[k] = r.get<double>("velocities");
    if (!std::isfinite(f.state.v[k]))
      r.fail("control point " + std::to_string(k / 3) + " has a velocity that is not finite");
  }
  if (flags & 1u) {
    f.stitch.resize(f.num_seg());
    for (auto& s : f.stitch) {
      s.row = r.get<int32_t>("stitch row");
      s.col = r.get<int32_t>("stitch column");
    }
  }
  if (flags & 2u) {
    const auto n = r.get<uint32_t>("knit description size");
    if (n > r.remaining()) r.fail("knit description size exceeds the file");
    const std::string_view text = r.bytes(n, "knit description");
    const nlohmann::json info = nlohmann::json::parse(text, nullptr, false);
    KnitInfo k;
    try {
      if (!info.is_object()) throw std::invalid_argument("not a JSON object");
      k.pattern = info.at("pattern").get<std::string>();
      k.rows = info.at("rows").get<int>();
      k.cols = info.at("cols").get<int>();
      k.in_the_round = info.at("in_the_round").get<bool>();
      k.segments_per_stitch = info.at("segments_per_stitch").get<int>();
      k.stitch_size_cm = info.at("stitch_size_cm").get<double>();
      k.shrink = info.at("shrink").get<double>();
      k.bind_off = info.value("bind_off", false);  // written since bind-offs exist
      k.cast_on = info.value("cast_on", false);    // and since cast-ons exist
      // and how it was being relaxed, since `relax --resume` goes on that way
      if (info.contains("relaxation")) k.relaxation = parse_relaxation(info.at("relaxation"));
    } catch (const nlohmann::json::exception& e) {
      r.fail("bad knit description: " + json_library_message(e.what()));
    } catch (const std::exception& e) {
      r.fail(std::string("bad knit description: ") + e.what());
    }
    f.knit = k;
    const int nseg = f.num_seg();
    if (static_cast<long long>(nseg) * 8 > static_cast<long long>(r.remaining()))
      r.fail("rest lengths exceed the file size");
    f.rest_length.resize(nseg);
    for (double& l : f.rest_length) {
      l = r.get<double>("rest length");
      if (!(l > 0) || !std::isfinite(l)) r.fail("a rest length is not a positive number");
    }
    const auto nglue = r.get<uint32_t>("glue count");
    if (nglue > r.remaining() / 56) r.fail("implausible glue count " + std::to_string(nglue));
    for (uint32_t g = 0; g < nglue; ++g) {
      Glue glue;
      glue.a.segment = r.get<int32_t>("glue segment");
      glue.a.t = r.get<double>("glue parameter");
      glue.b.segment = r.get<int32_t>("glue segment");
      glue.b.t = r.get<double>("glue parameter");
      for (int c = 0; c < 3; ++c) glue.gap[c] = r.get<double>("glue gap");
      glue.close_time = r.get<double>("glue close time");
      for (const YarnPoint& p : {glue.a, glue.b})
        if (p.segment < 0 || p.segment >= nseg || !(p.t >= 0 && p.t <= 1))
          r.fail("glue " + std::to_string(g) + " names a point off the yarn");
      if (!glue.gap.allFinite() || std::isnan(glue.close_time) || glue.close_time < 0)
        r.fail("glue " + std::to_string(g) + " has a bad gap or close time");
      f.glues.push_back(glue);
    }
  }
  if (flags & 4u) {
    const auto n = r.get<uint32_t>("run totals size");
    if (n > r.remaining()) r.fail("run totals size exceeds the file");
    const size_t at = r.pos();
    const nlohmann::json run = nlohmann::json::parse(r.bytes(n, "run totals"), nullptr, false);
    try {
      f.run = run_totals_from_json(run);
    } catch (const std::exception& e) {
      r.fail_at(at, std::string("bad run totals: ") + e.what());
    }
  }
  if (r.bytes(4, "end marker") != std::string_view(END_MAGIC, 4)) r.fail("bad end marker");
  if (version >= 3) r.get<uint32_t>("checksum");  // checked above
  if (r.remaining() != 0) r.fail("unexpected bytes after the end marker");
  return f;
}

}  // namespace knit
