#include "knit/io/csv.hpp"

#include <algorithm>
#include <charconv>
#include <stdexcept>
#include <string_view>
#include <system_error>

#include "knit/util/input_file.hpp"

namespace knit {
namespace {

std::string trim(std::string_view s) {
  const size_t b = s.find_first_not_of(" \t\r");
  if (b == std::string_view::npos) return {};
  const size_t e = s.find_last_not_of(" \t\r");
  return std::string(s.substr(b, e - b + 1));
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  size_t pos = 0;
  while (true) {
    const size_t comma = line.find(',', pos);
    out.push_back(trim(std::string_view(line).substr(pos, comma - pos)));
    if (comma == std::string::npos) break;
    pos = comma + 1;
  }
  return out;
}

}  // namespace

int CsvTable::column(const std::string& name, const std::string& file) const {
  for (size_t c = 0; c < columns.size(); ++c)
    if (columns[c] == name) return static_cast<int>(c);
  throw std::runtime_error(file + ": line 1: missing column '" + name + "'");
}

CsvTable read_csv(const std::string& path) {
  // a regular file of bounded size (a device such as /dev/zero would be read forever)
  const std::string text = read_input_file(path, MAX_CSV_BYTES, "CSV file");
  // what the messages show of the file: printable, and short (a binary file is one long
  // "line" of bytes)
  auto shown = [](const std::string& cell) { return printable(cell, 40); };
  CsvTable t;
  size_t line_no = 0, pos = 0;
  while (pos < text.size()) {
    const size_t end = std::min(text.find('\n', pos), text.size());
    const std::string line = text.substr(pos, end - pos);
    pos = end + 1;
    ++line_no;
    if (trim(line).empty()) continue;
    std::vector<std::string> cells = split(line);
    if (t.columns.empty()) {
      for (const auto& c : cells)
        if (c.empty())
          throw std::runtime_error(path + ": line " + std::to_string(line_no) +
                                   ": empty column name in the header");
      t.columns = std::move(cells);
      continue;
    }
    if (cells.size() != t.columns.size())
      throw std::runtime_error(path + ": line " + std::to_string(line_no) + ": " +
                               std::to_string(cells.size()) + " values, the header names " +
                               std::to_string(t.columns.size()) + " columns");
    std::vector<double> row;
    for (size_t c = 0; c < cells.size(); ++c) {
      double v = 0;
      const std::string& s = cells[c];
      const auto res = std::from_chars(s.data(), s.data() + s.size(), v);
      if (s.empty() || res.ec != std::errc() || res.ptr != s.data() + s.size())
        throw std::runtime_error(path + ": line " + std::to_string(line_no) + ": column '" +
                                 shown(t.columns[c]) + "': '" + shown(s) + "' is not a number");
      row.push_back(v);
    }
    t.rows.push_back(std::move(row));
  }
  if (t.columns.empty()) throw std::runtime_error(path + ": empty CSV file (no header)");
  if (t.rows.empty()) throw std::runtime_error(path + ": no data rows after the header");
  return t;
}

}  // namespace knit
