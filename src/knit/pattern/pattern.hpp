#pragma once
// Knit patterns (MODEL.md §6): which stitches are knit and which purl, row by row, always
// as seen from the FRONT of the fabric. A pattern names what the fabric is, not how a
// knitter made it: stockinette has every loop pulled through to the same (front) face,
// whatever the direction the yarn runs in each row.
#include <string>
#include <string_view>
#include <vector>

namespace knit {

/// A chart of 'k' (knit: the loop is pulled through from back to front, its legs show on
/// the front face) and 'p' (purl: pulled through from front to back), as seen from the
/// front. rows[0] is the first knitted row, at the bottom of the fabric; rows[r][c] is
/// column c counted from the left as seen from the front. All rows have the same length.
struct Pattern {
  std::vector<std::string> rows;
  /// The yarn knits row 0 from the right to the left, as seen from the front (a knitout
  /// program whose first pass goes towards lower needles); the generator then lays the
  /// mirror image of its rightward yarn, the same stitches with the yarn running the other
  /// way in every row. A chart's rows start at the left.
  bool first_row_leftward = false;
  /// Several yarns (a knitout program's stripes): the yarn that knits each row (0, 1, …, in
  /// the order they first knit), and whether it knits the row from the right. Empty: one
  /// yarn knits every row, to and fro from the side first_row_leftward says. Each yarn's
  /// rows alternate in direction; between two rows that are not neighbours it is carried up
  /// the edge where it ended the first. A flat piece only, laid at its own size.
  std::vector<int> row_yarn = {};
  std::vector<char> row_leftward = {};

  int num_rows() const { return static_cast<int>(rows.size()); }
  int num_cols() const { return rows.empty() ? 0 : static_cast<int>(rows.front().size()); }
  /// true for a knit stitch (as seen from the front) at (row, col).
  bool is_knit(int row, int col) const { return rows[row][col] == 'k'; }
  /// 1 + the largest row_yarn (1 when it is empty).
  int num_yarns() const;
};

/// Parses a chart: one line per row, one character per stitch, 'k' or 'p' (either case);
/// '#' starts a comment to the end of the line; blank lines are ignored; spaces and tabs
/// are ignored. Lines are drawn as the fabric looks from the front, like a knitting chart:
/// the LAST row line of the text is row 0 (the bottom), its first character column 0 (the
/// left). Throws std::invalid_argument naming `source_name`, line and column on an unknown
/// character, rows of different lengths or an empty chart.
Pattern parse_chart(std::string_view text, const std::string& source_name);

/// The built-in patterns: "stockinette" (all k), "reverse_stockinette" (all p), "garter"
/// (rows of k and p alternating), "rib1x1" (kp), "rib2x2" (kkpp), "seed" (kp / pk).
Pattern builtin_pattern(std::string_view name);
/// Names accepted by builtin_pattern, in a fixed order.
std::vector<std::string> builtin_pattern_names();

/// A built-in pattern by name, or else a knitout program (a path ending in ".k", or a file
/// whose first line is ";!knitout-": its stitches, knitout.hpp) or a chart file
/// (parse_chart). Throws naming the argument when it
/// is none of them.
Pattern load_pattern(const std::string& name_or_path);

/// Repeats `pattern` to fill rows × cols: result(r, c) = pattern(r mod R, c mod C).
Pattern tile(const Pattern& pattern, int rows, int cols);

}  // namespace knit
