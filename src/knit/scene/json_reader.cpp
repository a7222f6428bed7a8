#include "knit/scene/json_reader.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <set>
#include <sstream>
#include <vector>

#include "knit/model/params.hpp"
#include "knit/util/input_file.hpp"

namespace knit {

namespace {

// A short description of a value for messages: its type and a bounded prefix, never the
// whole value (a value may be megabytes long or nested thousands deep).
std::string describe(const nlohmann::json& v) {
  switch (v.type()) {
    case nlohmann::json::value_t::object:
      return "an object with " + std::to_string(v.size()) + (v.size() == 1 ? " key" : " keys");
    case nlohmann::json::value_t::array:
      return "an array of " + std::to_string(v.size()) + (v.size() == 1 ? " element" : " elements");
    case nlohmann::json::value_t::string: {
      const std::string& str = v.get_ref<const std::string&>();
      std::string shown = str.size() > 24 ? str.substr(0, 24) : str;
      // keep the prefix printable: other bytes as \xNN
      std::string out;
      for (unsigned char c : shown) {
        if (c >= 0x20 && c < 0x7f && c != '"') {
          out += static_cast<char>(c);
        } else {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\x%02X", c);
          out += buf;
        }
      }
      return "the string \"" + out + (str.size() > 24 ? "...\"" : "\"");
    }
    case nlohmann::json::value_t::boolean:
      return v.get<bool>() ? "true" : "false";
    case nlohmann::json::value_t::null:
      return "null";
    default: {
      if (v.is_number_float()) return short_number(v.get<double>());
      return v.dump();  // an integer: at most 20 characters
    }
  }
}

}  // namespace

void JsonReader::fail(const std::string& expected) const {
  throw InputError(m_source + ": " + (m_path.empty() ? std::string("(top level)") : m_path) + ": " +
                   expected);
}

JsonReader JsonReader::at(const std::string& key) const {
  require_object();
  if (!m_value.contains(key))
    JsonReader(m_value, m_source, m_path.empty() ? key : m_path + "." + key)
        .fail("missing required field");
  return JsonReader(m_value.at(key), m_source, m_path.empty() ? key : m_path + "." + key);
}

JsonReader JsonReader::at(size_t index) const {
  require_array();
  if (index >= m_value.size()) fail("index " + std::to_string(index) + " out of range");
  return JsonReader(m_value.at(index), m_source, m_path + "[" + std::to_string(index) + "]");
}

void JsonReader::require_object() const {
  if (!m_value.is_object()) fail("expected an object, got " + describe(m_value));
}

void JsonReader::require_array(size_t min_size) const {
  if (!m_value.is_array()) fail("expected an array, got " + describe(m_value));
  if (m_value.size() < min_size)
    fail("expected at least " + std::to_string(min_size) + " elements, got " +
         std::to_string(m_value.size()));
}

void JsonReader::allow_keys(std::initializer_list<const char*> allowed) const {
  allow_keys(std::vector<std::string>(allowed.begin(), allowed.end()));
}

void JsonReader::allow_keys(const std::vector<std::string>& allowed) const {
  require_object();
  for (const auto& item : m_value.items()) {
    const std::string& key = item.key();  // a named variable: clang 14 cannot capture bindings
    if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
      std::string list;
      for (const std::string& a : allowed) list += (list.empty() ? "" : ", ") + a;
      JsonReader(m_value, m_source, m_path.empty() ? key : m_path + "." + key)
          .fail("unknown key (expected one of: " + list + ")");
    }
  }
}

double JsonReader::number() const {
  if (!m_value.is_number()) fail("expected a number, got " + describe(m_value));
  const double x = m_value.get<double>();
  if (!std::isfinite(x)) fail("expected a finite number");
  return x;
}

double JsonReader::positive(bool allow_zero) const {
  const double x = number();
  if (allow_zero ? x < 0 : x <= 0)
    fail(std::string("expected a ") + (allow_zero ? "non-negative" : "positive") + " number, got " +
         describe(m_value));
  return x;
}

int JsonReader::integer(int min_value) const {
  return integer(min_value, 1'000'000'000);
}

int JsonReader::integer(int min_value, int max_value) const {
  if (!m_value.is_number_integer()) fail("expected an integer, got " + describe(m_value));
  // an unsigned value beyond the signed range is out of range too, not wrapped negative
  const bool huge = m_value.is_number_unsigned() &&
                    m_value.get<std::uint64_t>() > static_cast<std::uint64_t>(max_value);
  const long long x = huge ? 0 : m_value.get<long long>();
  if (huge || x < min_value || x > max_value)
    fail(max_value == 1'000'000'000
             ? "expected an integer >= " + std::to_string(min_value) + ", got " + m_value.dump()
             : "expected an integer from " + std::to_string(min_value) + " to " +
                   std::to_string(max_value) + ", got " + m_value.dump());
  return static_cast<int>(x);
}

double JsonReader::number_in(double lo, double hi, const std::string& unit) const {
  const double x = number();
  if (!(x >= lo && x <= hi))
    fail("expected a value in [" + short_number(lo) + ", " + short_number(hi) + "]" +
         (unit.empty() ? "" : " " + unit) + ", got " + short_number(x));
  return x;
}

bool JsonReader::boolean() const {
  if (!m_value.is_boolean()) fail("expected true or false, got " + describe(m_value));
  return m_value.get<bool>();
}

std::string JsonReader::string() const {
  if (!m_value.is_string()) fail("expected a string, got " + describe(m_value));
  return m_value.get<std::string>();
}

Eigen::Vector3d JsonReader::vec3() const {
  if (!m_value.is_array() || m_value.size() != 3)
    fail("expected an array of 3 numbers [x, y, z], got " + describe(m_value));
  return {at(size_t(0)).number(), at(size_t(1)).number(), at(size_t(2)).number()};
}

Eigen::Vector3d JsonReader::coordinates(double limit, const std::string& unit) const {
  const Eigen::Vector3d v = vec3();
  for (size_t k = 0; k < 3; ++k)
    if (!(std::abs(v[static_cast<Eigen::Index>(k)]) <= limit))
      at(k).fail("expected a coordinate within ±" + short_number(limit) + " " + unit + ", got " +
                 short_number(v[static_cast<Eigen::Index>(k)]));
  return v;
}

nlohmann::json parse_json_file(const std::string& path) {
  std::string text;
  try {
    text = read_input_file(path, MAX_SCENE_BYTES, "JSON file");
  } catch (const std::runtime_error& e) {
    throw InputError(e.what());
  }
  return parse_json_text(text, path);
}

namespace {

// line and column (1-based) of byte `offset` of `text`
std::string line_and_column(const std::string& text, size_t offset) {
  size_t line = 1, col = 1;
  for (size_t k = 0; k < offset && k < text.size(); ++k) {
    if (text[k] == '\n') {
      ++line;
      col = 1;
    } else {
      ++col;
    }
  }
  return std::to_string(line) + ":" + std::to_string(col);
}

// the byte offset of the `n`-th (0-based) object key of `text`, a JSON document valid up
// to there (a string followed by ':' outside any string is a key)
size_t key_offset(const std::string& text, size_t n) {
  size_t count = 0;
  for (size_t k = 0; k < text.size(); ++k) {
    if (text[k] != '"') continue;
    const size_t start = k;
    for (++k; k < text.size() && text[k] != '"'; ++k)
      if (text[k] == '\\') ++k;
    size_t after = k + 1;
    while (after < text.size() && std::isspace(static_cast<unsigned char>(text[after]))) ++after;
    if (after < text.size() && text[after] == ':' && count++ == n) return start;
  }
  return text.size();
}

// the parser library's message in knitsim's words: "[json.exception.parse_error.101]
// parse error at line 1, column 5: syntax error while parsing value - invalid literal;
// last read: 'tru'" → "invalid literal (in a value; last read: 'tru')", bytes that do
// not print escaped, and cut short (the token quoted may be megabytes long)
std::string parser_message(const std::string& what) {
  std::string m = what;
  if (m.rfind("[json.exception.", 0) == 0 && m.find("] ") != std::string::npos)
    m.erase(0, m.find("] ") + 2);
  if (m.rfind("parse error", 0) == 0 && m.find(": ") != std::string::npos)
    m.erase(0, m.find(": ") + 2);
  std::string where;
  if (m.rfind("syntax error while parsing ", 0) == 0) {
    const size_t dash = m.find(" - ");
    if (dash != std::string::npos) {
      where = m.substr(27, dash - 27);
      m.erase(0, dash + 3);
    }
  }
  std::string last;
  if (const size_t at = m.find("; last read: "); at != std::string::npos) {
    // the token the lexer read, from its last line on (the library quotes from where the
    // token began, line ends as <U+000A>): "last read: 'tru'"
    std::string token = m.substr(at + 13);
    m.erase(at);
    if (token.size() >= 2 && token.front() == '\'' && token.back() == '\'')
      token = token.substr(1, token.size() - 2);
    const std::string nl = "<U+000A>";
    while (token.size() >= nl.size() && token.compare(token.size() - nl.size(), nl.size(), nl) == 0)
      token.erase(token.size() - nl.size());
    if (const size_t cut = token.rfind(nl); cut != std::string::npos)
      token.erase(0, cut + nl.size());
    const size_t first = token.find_first_not_of(" \t");
    last = "last read: '" + (first == std::string::npos ? token : token.substr(first)) + "'";
  }
  std::string out = m;
  if (!where.empty() || !last.empty()) {
    out += " (";
    if (!where.empty())
      out += std::string("in ") +
             (std::string("aeiou").find(where[0]) != std::string::npos ? "an " : "a ") + where;
    if (!where.empty() && !last.empty()) out += "; ";
    out += last;
    out += ")";
  }
  return printable(out, 200);
}

}  // namespace

nlohmann::json parse_json_text(const std::string& text, const std::string& path) {
  // nesting deeper than any scene needs is refused while parsing, before the document is
  // built (deep documents exhaust the stack of anything that walks them recursively); a
  // key given twice in one object is refused where it is given the second time (the
  // library would keep one of the two silently)
  struct Open {
    bool object;
    std::set<std::string> keys;
    std::string key;   // the member being read (objects)
    size_t index = 0;  // the element being read (arrays)
  };
  std::vector<Open> open;
  size_t keys_read = 0;
  auto field_path = [&]() {
    std::string p;
    for (const Open& o : open)
      p += o.object ? (p.empty() ? "" : ".") + printable(o.key)
                    : "[" + std::to_string(o.index) + "]";
    return p;
  };
  auto element_read = [&]() {
    if (!open.empty() && !open.back().object) ++open.back().index;
  };
  auto callback = [&](int depth, nlohmann::json::parse_event_t event, nlohmann::json& parsed) {
    using E = nlohmann::json::parse_event_t;
    if (depth > MAX_JSON_DEPTH)
      throw InputError(path + ": JSON nested more than " + std::to_string(MAX_JSON_DEPTH) +
                       " levels deep (a scene needs a few)");
    switch (event) {
      case E::object_start:
        open.push_back({true, {}, {}, 0});
        break;
      case E::array_start:
        open.push_back({false, {}, {}, 0});
        break;
      case E::key: {
        Open& o = open.back();
        o.key = parsed.get<std::string>();
        if (!o.keys.insert(o.key).second)
          throw InputError(path + ":" + line_and_column(text, key_offset(text, keys_read)) + ": " +
                           field_path() + ": the key \"" + printable(o.key) +
                           "\" is given twice in one object (each key may appear once)");
        ++keys_read;
        break;
      }
      case E::object_end:
      case E::array_end:
        open.pop_back();
        element_read();
        break;
      case E::value:
        element_read();
        break;
    }
    return true;
  };
  try {
    return nlohmann::json::parse(text, callback);
  } catch (const nlohmann::json::parse_error& e) {
    // the byte offset as line and column
    throw InputError(path + ":" + line_and_column(text, e.byte > 0 ? e.byte - 1 : 0) +
                     ": malformed JSON: " + parser_message(e.what()));
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path + ": malformed JSON: " + parser_message(e.what()));
  }
}

}  // namespace knit
