#include "knit/scene/json_reader.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "knit/io/input_file.hpp"
#include "knit/model/params.hpp"

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

// the parser's message quotes the offending token, which may be megabytes long
std::string shorten(const std::string& message) {
  constexpr size_t MAX = 200;
  return message.size() <= MAX ? message : message.substr(0, MAX) + "…";
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
  require_object();
  for (const auto& item : m_value.items()) {
    const std::string& key = item.key();  // a named variable: clang 14 cannot capture bindings
    if (std::none_of(allowed.begin(), allowed.end(), [&](const char* a) { return key == a; })) {
      std::string list;
      for (const char* a : allowed) list += std::string(list.empty() ? "" : ", ") + a;
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
  if (!m_value.is_number_integer()) fail("expected an integer, got " + describe(m_value));
  const auto x = m_value.get<long long>();
  if (x < min_value || x > 1'000'000'000)
    fail("expected an integer >= " + std::to_string(min_value) + ", got " + std::to_string(x));
  return static_cast<int>(x);
}

int JsonReader::integer(int min_value, int max_value) const {
  const int x = integer(min_value);
  if (x > max_value)
    fail("expected an integer from " + std::to_string(min_value) + " to " +
         std::to_string(max_value) + ", got " + std::to_string(x));
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

nlohmann::json parse_json_file(const std::string& path) {
  std::string text;
  try {
    text = read_input_file(path, MAX_SCENE_BYTES, "JSON file");
  } catch (const std::runtime_error& e) {
    throw InputError(e.what());
  }
  return parse_json_text(text, path);
}

nlohmann::json parse_json_text(const std::string& text, const std::string& path) {
  // nesting deeper than any scene needs is refused while parsing, before the document is
  // built (deep documents exhaust the stack of anything that walks them recursively)
  auto limit_depth = [&](int depth, nlohmann::json::parse_event_t, nlohmann::json&) {
    if (depth > MAX_JSON_DEPTH)
      throw InputError(path + ": JSON nested more than " + std::to_string(MAX_JSON_DEPTH) +
                       " levels deep (a scene needs a few)");
    return true;
  };
  try {
    return nlohmann::json::parse(text, limit_depth);
  } catch (const nlohmann::json::parse_error& e) {
    // translate the byte offset into line and column
    size_t line = 1, col = 1;
    for (size_t k = 0; k + 1 < e.byte && k < text.size(); ++k) {
      if (text[k] == '\n') {
        ++line;
        col = 1;
      } else {
        ++col;
      }
    }
    throw InputError(path + ":" + std::to_string(line) + ":" + std::to_string(col) +
                     ": malformed JSON: " + shorten(e.what()));
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path + ": malformed JSON: " + shorten(e.what()));
  }
}

}  // namespace knit
