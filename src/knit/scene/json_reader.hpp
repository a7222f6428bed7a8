#pragma once
// Strict reading of JSON input: every error names the source file, the field path
// (e.g. yarns[2].line.segments) and what was expected; unknown keys are errors.
#include <Eigen/Core>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

namespace knit {

/// Bad user input: the message names file, field and what was expected.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class JsonReader {
 public:
  JsonReader(const nlohmann::json& value, std::string source, std::string path = "")
      : m_value(value), m_source(std::move(source)), m_path(std::move(path)) {}

  const nlohmann::json& value() const { return m_value; }
  const std::string& path() const { return m_path; }
  bool has(const std::string& key) const { return m_value.is_object() && m_value.contains(key); }
  /// The member `key` (required).
  JsonReader at(const std::string& key) const;
  /// Element `index` of an array.
  JsonReader at(size_t index) const;
  size_t size() const { return m_value.size(); }

  void require_object() const;
  void require_array(size_t min_size = 0) const;
  /// Throws if the object has keys outside `allowed`, naming the first unknown one.
  void allow_keys(std::initializer_list<const char*> allowed) const;
  void allow_keys(const std::vector<std::string>& allowed) const;

  double number() const;
  /// A finite number > 0 (or ≥ 0 when `allow_zero`).
  double positive(bool allow_zero = false) const;
  int integer(int min_value) const;
  /// An integer in [min_value, max_value].
  int integer(int min_value, int max_value) const;
  /// A finite number in [lo, hi]; the message names the range (in `unit`) and the value.
  double number_in(double lo, double hi, const std::string& unit = "") const;
  bool boolean() const;
  std::string string() const;
  Eigen::Vector3d vec3() const;
  /// A point or vector [x, y, z] whose coordinates are each within ±`limit` (cm unless
  /// `unit` says otherwise); the message names the element and its value.
  Eigen::Vector3d coordinates(double limit, const std::string& unit = "cm") const;

  double number_or(const std::string& key, double fallback) const {
    return has(key) ? at(key).number() : fallback;
  }

  [[noreturn]] void fail(const std::string& expected) const;

 private:
  const nlohmann::json& m_value;
  std::string m_source, m_path;
};

/// Largest coordinate (and size) a scene's yarns and objects may have, either way (cm).
inline constexpr double MAX_SCENE_COORDINATE = 1e6;

/// Deepest nesting of arrays and objects a JSON input may have.
inline constexpr int MAX_JSON_DEPTH = 64;

/// Parses a JSON file (a regular file of at most MAX_SCENE_BYTES); syntax errors name the
/// file, line and column, in knitsim's words (not the parser library's); nesting deeper
/// than MAX_JSON_DEPTH is refused, and so is a key given twice in one object (named with
/// its field path, line and column).
nlohmann::json parse_json_file(const std::string& path);
/// The same for text already in memory; `path` names it in messages.
nlohmann::json parse_json_text(const std::string& text, const std::string& path);

}  // namespace knit
