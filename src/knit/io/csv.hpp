#pragma once
// Numeric CSV tables: the logs (log.csv), stretch curves (stretch.csv) and measured curves
// knitsim reads back.
#include <string>
#include <vector>

namespace knit {

/// A numeric CSV table with one header line of column names.
struct CsvTable {
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;  ///< each row has columns.size() values
  /// Index of a column; throws std::runtime_error naming `file` when it is missing.
  int column(const std::string& name, const std::string& file) const;
};

/// Reads a numeric CSV (comma separated, header first, blank lines skipped), a regular file
/// of at most MAX_CSV_BYTES. Throws std::runtime_error naming the file and line on malformed
/// input, with what it quotes of the file printable and short.
CsvTable read_csv(const std::string& path);

}  // namespace knit
