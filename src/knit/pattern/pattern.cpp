#include "knit/pattern/pattern.hpp"

#include "knit/pattern/knitout.hpp"
#include "knit/util/input_file.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <stdexcept>

namespace knit {

namespace {

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& ch : out) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return out;
}

}  // namespace

Pattern parse_chart(std::string_view text, const std::string& source_name) {
  struct Line {
    std::string stitches;
    int number;
  };
  std::vector<Line> lines;
  int line_no = 0;
  size_t pos = 0;
  // a UTF-8 byte-order mark (editors on some systems write one) is not part of the chart
  if (text.substr(0, 3) == "\xEF\xBB\xBF") pos = 3;
  while (pos <= text.size()) {
    const size_t end = std::min(text.find('\n', pos), text.size());
    std::string_view raw = text.substr(pos, end - pos);
    ++line_no;
    std::string stitches;
    for (size_t i = 0; i < raw.size(); ++i) {
      const char ch = raw[i];
      if (ch == '#') break;
      if (ch == ' ' || ch == '\t' || ch == '\r') continue;
      const char lc = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
      if (lc != 'k' && lc != 'p') {
        std::ostringstream msg;
        msg << source_name << ":" << line_no << ":" << (i + 1) << ": unknown stitch ";
        const auto uc = static_cast<unsigned char>(ch);
        if (uc >= 0x20 && uc < 0x7f) {
          msg << "'" << ch << "'";
        } else {
          // a byte that does not print (binary data, UTF-8): its value, not the raw byte
          char buf[16];
          std::snprintf(buf, sizeof buf, "byte 0x%02X", uc);
          msg << buf << (uc >= 0x80 ? " (not ASCII; is this a text chart?)" : "");
        }
        msg << " (expected 'k' for knit or 'p' for purl, '#' for a comment)";
        throw std::invalid_argument(msg.str());
      }
      stitches.push_back(lc);
    }
    if (!stitches.empty()) lines.push_back({std::move(stitches), line_no});
    if (end == text.size()) break;
    pos = end + 1;
  }
  if (lines.empty())
    throw std::invalid_argument(source_name +
                                ": empty chart (expected at least one row of 'k'/'p' stitches)");
  const size_t width = lines.front().stitches.size();
  for (const Line& l : lines)
    if (l.stitches.size() != width) {
      std::ostringstream msg;
      msg << source_name << ":" << l.number << ":" << (std::min(width, l.stitches.size()) + 1)
          << ": row has " << l.stitches.size() << " stitches, expected " << width << " like line "
          << lines.front().number << " (all rows must have the same length)";
      throw std::invalid_argument(msg.str());
    }
  // the chart is drawn top row first: the last line is row 0
  Pattern p;
  for (auto it = lines.rbegin(); it != lines.rend(); ++it) p.rows.push_back(it->stitches);
  return p;
}

std::vector<std::string> builtin_pattern_names() {
  return {"stockinette", "reverse_stockinette", "garter", "rib1x1", "rib2x2", "seed"};
}

Pattern builtin_pattern(std::string_view name) {
  const std::string n = lower(name);
  if (n == "stockinette") return {{"k"}};
  if (n == "reverse_stockinette") return {{"p"}};
  if (n == "garter") return {{"k", "p"}};
  if (n == "rib1x1") return {{"kp"}};
  if (n == "rib2x2") return {{"kkpp"}};
  if (n == "seed") return {{"kp", "pk"}};
  std::string list;
  for (const auto& b : builtin_pattern_names()) list += (list.empty() ? "" : ", ") + b;
  throw std::invalid_argument("unknown built-in pattern '" + std::string(name) +
                              "' (expected one of " + list + ")");
}

Pattern load_pattern(const std::string& name_or_path) {
  const auto names = builtin_pattern_names();
  if (std::find(names.begin(), names.end(), lower(name_or_path)) != names.end())
    return builtin_pattern(name_or_path);
  if (!std::filesystem::exists(name_or_path)) {
    std::string list;
    for (const auto& b : names) list += (list.empty() ? "" : ", ") + b;
    throw std::invalid_argument("pattern '" + name_or_path + "': not a built-in pattern (" + list +
                                ") and no chart file exists at that path");
  }
  if (is_knitout_path(name_or_path)) return load_knitout(name_or_path).pattern;
  std::string text;
  try {
    text = read_input_file(name_or_path, MAX_CHART_BYTES, "chart file");
  } catch (const std::runtime_error& e) {
    throw std::invalid_argument(e.what());
  }
  return parse_chart(text, name_or_path);
}

int Pattern::num_yarns() const {
  return row_yarn.empty() ? 1 : 1 + *std::max_element(row_yarn.begin(), row_yarn.end());
}

Pattern tile(const Pattern& pattern, int rows, int cols) {
  if (pattern.num_rows() == 0 || pattern.num_cols() == 0)
    throw std::invalid_argument("tile: the pattern is empty");
  if (rows < 1 || cols < 1)
    throw std::invalid_argument("tile: rows and cols must be at least 1, got " +
                                std::to_string(rows) + " x " + std::to_string(cols));
  if (!pattern.row_yarn.empty() && rows != pattern.num_rows())
    throw std::invalid_argument("tile: a pattern of " + std::to_string(pattern.num_yarns()) +
                                " yarns is laid at its own " + std::to_string(pattern.num_rows()) +
                                " rows, not " + std::to_string(rows));
  Pattern out;
  out.first_row_leftward = pattern.first_row_leftward;
  out.row_yarn = pattern.row_yarn;
  out.row_leftward = pattern.row_leftward;
  out.rows.assign(rows, std::string(cols, 'k'));
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c)
      out.rows[r][c] = pattern.rows[r % pattern.num_rows()][c % pattern.num_cols()];
  return out;
}

}  // namespace knit
