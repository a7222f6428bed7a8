#include "knit/analysis/rest_reference.hpp"

#include "knit/util/input_file.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <stdexcept>
#include <string_view>

namespace knit {

nlohmann::json read_rest_reference(const std::string& dir, const std::string& pattern, int rows,
                                   int cols) {
  const std::string path = dir + "/" + pattern + "/summary.json";
  const auto fail = [&](const std::string& what) { throw std::runtime_error(path + ": " + what); };
  std::ifstream in(path);
  if (!in)
    fail("cannot be read (the reference relaxation of " + pattern +
         "; scripts/relax_reference.sh makes one)");
  nlohmann::json s;
  try {
    s = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    fail("not JSON (" + json_library_message(e.what()) + ")");
  }
  if (!s.is_object() || !s.contains("pattern") || !s.contains("relaxed") || !s.contains("rows") ||
      !s.contains("cols"))
    fail("not the summary of a `knitsim relax` run (no pattern, rows, cols or relaxed)");
  if (s["pattern"] != pattern)
    fail("a relaxation of " + s["pattern"].dump() + ", not of " + pattern);
  if (s["rows"] != rows || s["cols"] != cols)
    fail("a " + s["rows"].dump() + "×" + s["cols"].dump() + " sample, not " + std::to_string(rows) +
         "×" + std::to_string(cols));
  if (s["relaxed"] != true) fail("not at rest (\"relaxed\": " + s["relaxed"].dump() + ")");
  for (const char* key : REST_SHAPE_KEYS)
    if (!s.contains(key) || !s[key].is_number() || !std::isfinite(s[key].get<double>()))
      fail(std::string("no finite \"") + key + "\"");
  return s;
}

nlohmann::json compare_rest_shape(const nlohmann::json& run, const nlohmann::json& reference) {
  constexpr std::string_view AGREEMENT[] = {"course_length_cm", "wale_length_cm", "stitch_width_cm",
                                            "row_height_cm"};
  nlohmann::json diff = nlohmann::json::object();
  double worst = 0;
  for (const char* key : REST_SHAPE_KEYS) {
    if (!run.contains(key) || !reference.contains(key) || !run[key].is_number() ||
        !reference[key].is_number())
      continue;
    const double a = run[key].get<double>(), b = reference[key].get<double>();
    if (!std::isfinite(a) || !std::isfinite(b)) continue;
    if (std::string_view(key) == "edge_curl") {
      diff["edge_curl_difference"] = a - b;
    } else if (b != 0) {
      diff[key] = a / b - 1;
      if (std::find(std::begin(AGREEMENT), std::end(AGREEMENT), key) != std::end(AGREEMENT))
        worst = std::max(worst, std::abs(a / b - 1));
    }
  }
  diff["max_abs_width_height_gauge"] = worst;
  return diff;
}

}  // namespace knit
