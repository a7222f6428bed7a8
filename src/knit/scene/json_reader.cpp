#include "knit/scene/json_reader.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

namespace knit {

namespace {
std::string describe(const nlohmann::json& v) {
  std::string s = v.dump();
  if (s.size() > 40) s = s.substr(0, 37) + "...";
  return s;
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
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open file");
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  try {
    return nlohmann::json::parse(text);
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
                     ": malformed JSON: " + e.what());
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path + ": malformed JSON: " + e.what());
  }
}

}  // namespace knit
