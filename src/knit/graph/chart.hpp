#pragma once
// Hand-knitting charts with real stitches: a chart front end that builds the knit graph
// (knit_graph.hpp) through the same edits as the knitout interpreter — a stitch symbol is
// a graph edit (k2tog = a loop with two parents, yo = a new loop with none, C4F = four
// loops whose order changes, …). docs/charts.md has the format with examples.
//
// THE FORMAT (text, UTF-8/ASCII; one line per chart row)
//   - '#' starts a comment to the end of the line; blank lines are ignored.
//   - Header lines `key: value`, before the first row: `knit: flat` (default: worked back
//     and forth) or `knit: round` (every row a round worked from the right side);
//     `cells: rs` (default: each cell shows the stitch as it looks from the right side, as
//     printed charts do — on a wrong-side row the knitter works the opposite: a `k` cell
//     is purled) or `cells: worked` (each cell names what the knitter does on that row, as
//     written instructions do: `k` on a wrong-side row shows as a purl from the front —
//     there every face is the opposite, a slip's float lies on the other side, an m1
//     leans the other way, a cable X/Y worked from the wrong side shows from the front
//     as a Y/X cable crossing the same way, and a decrease keeps its parents' order);
//     `yarn: NAME` (the yarn of cells that name none; default A).
//   - Row lines: cells separated by spaces, tabs or commas. The LAST row line is row 1 at
//     the bottom; the chart is a picture of the right side: a line's first cell is at the
//     left of the fabric as seen from the front. Flat: odd rows are right-side rows, worked
//     (read) right to left; even rows are wrong-side rows, worked left to right. Round:
//     every row is worked right to left.
//   - A cell: SYMBOL or SYMBOL@YARN (case-insensitive symbols; '-' and '_' inside a symbol
//     are ignored: sl-wyif = slwyif). A row line may begin with `@YARN`: that row's yarn.
//     A word made only of the letters k and p (kkpp) is that many one-stitch cells, so the
//     k/p charts of knit/pattern/pattern.hpp read the same here.
//   - Every row line covers the same number of grid columns. A cell covers one column,
//     a cable or twist as many as its stitches (c4f covers 4). Where a row has fewer
//     stitches than the grid, `.` cells (no stitch: an empty square) fill it; the stitches
//     of a row need not sit above the ones they are worked into — a row simply works the
//     live stitches in order, and the columns place the new loops (Loop::needle = column,
//     1 = the leftmost).
//   - Each row must work exactly the live stitches left by the row below: the sum of what
//     its cells take (k: 1, k2tog: 2, yo: 0, c6f: 6, …) equals the live stitches.
//
// SYMBOLS (takes → makes; parents listed bottom first: the last lies on top, in front as
// seen from the front; "left"/"right" as seen from the front)
//   k, p                 1 → 1  knit / purl face
//   ktbl, ptbl           1 → 1  twisted: pulled through its parent's back leg, so the
//                               parent's legs cross (ChartResult::twisted)
//   k2tog, p2tog         2 → 1  right-leaning: parents {right, left} (left on top)
//   ssk, ssp             2 → 1  left-leaning: parents {left, right} (right on top)
//   k3tog, p3tog         3 → 1  parents {right, middle, left}
//   sssk                 3 → 1  parents {left, middle, right}
//   sk2p                 3 → 1  sl1-k2tog-psso: {middle, left, right} (right on top)
//   cdd (s2kp)           3 → 1  centred: {left, right, middle} (middle on top)
//   yo                   0 → 1  a NEW loop with no parents
//   m1l, m1r (m1 = m1l)  0 → 1  a NEW loop from the bar between the stitches either side
//                               (ChartResult::increases names them, and the lean)
//   sl (= slwyib), slwyif 1 → 1  the stitch carries up unchanged; the yarn passes it: a
//                               MISS step, the float behind (wyib: on the wrong side) or
//                               in front (wyif: on the right side), ChartResult::floats
//   tuck                 1 → 1  the stitch carries up with a TUCK loop laid on it; the next
//                               row's stitch there is pulled through both
//   bo                   1 → 0  bind off: a knit whose parents are the stitch and the
//                               previous bound-off loop (passed over it, on top); the
//                               next stitch made in the row passes through the last one;
//                               a bind-off that ends the row is fastened off (the yarn is
//                               cut: ChartResult::fastened_off; that yarn name used later
//                               is a new piece of yarn)
//   -                    1 → 1  unworked: the stitch stays on the needle (short rows);
//                               only at the ends of a row, flat only
//   w&t (wt)             1 → 1  wrap and turn: the stitch is wrapped (a TUCK loop on it)
//                               and the row turns: only unworked cells may follow
//   ds                   1 → 1  German short rows' double stitch, the first stitch after a
//                               turn: the yarn pulled over it (a TUCK loop on it)
//   .                    0 → 0  no stitch
//   cAF, cAB (A even)    A → A  cables: A/2 stitches cross A/2 (c4f, c6b, c8f, …)
//   cX/YF, cX/YB               X stitches pass in front of Y: F (left cross): the right X
//                               go left in front; B (right cross): the left X go right in
//                               front. Also X/YLC = cX/YF, X/YRC = cX/YB.
//   tAR, tAL, tX/YR, tX/YL     twists: as cX/YB (R) and cX/YF (L), the stitches that pass
//                               behind purled (t2r = t1/1r; X/YRPC, X/YLPC likewise)
//   Cables record a Crossing (the loop in front, the loop behind) for every new loop of
//   the front group with every new loop of the back group.
//
// WHAT THE GRAPH HOLDS: one bed (FRONT), Loop::needle = the cell's column; a cast-on row
// (NEW loops, line 0) made left to right by the yarn of row 1's first stitch; for chart
// loops Loop::line = Loop::pass = Loop::course = the chart row (1 = the bottom row: the
// graph requires a yarn's steps in non-decreasing line order, and text lines run the
// other way) — ChartResult::row_line gives each row's text line. Direction: MINUS on
// right-side rows (worked right to left), PLUS on wrong-side rows. Faces are as seen from
// the front (right side). A yarn per yarn name (its carrier name), brought in at the row
// it is first used; stranded colourwork: between two stitches of a yarn in a row, the
// stitches of other yarns it passes are MISS steps on it (the float on the wrong side).
//
// Refused with std::invalid_argument "SOURCE:LINE:COL: what was expected" (COL: the text
// column of the cell, with its index in the line): an unknown symbol or header, a row
// whose cells take more or fewer stitches than are live, rows of different widths, a
// cable wider than MAX_CABLE_STITCHES or than the stitches left, an m1 without a stitch on
// each side, a bind-off followed by a yo, m1, slip, tuck, w&t or ds, an
// unworked cell between worked ones, a short row that does not start where the yarn
// turned, a chart over MAX_CHART_TEXT_BYTES, MAX_CHART_LOOPS (loops, or floats) or
// MAX_CHART_YARNS.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "knit/graph/knit_graph.hpp"

namespace knit::graph {

/// The largest chart text read (bytes).
inline constexpr std::size_t MAX_CHART_TEXT_BYTES = 4u << 20;
/// The most loops a chart may make (the graph takes about 100 bytes per loop).
inline constexpr std::size_t MAX_CHART_LOOPS = 4u << 20;
/// The most yarn names a chart may use (each a yarn; the floats of stranded colourwork
/// grow with their number), and the most floats it may make: MAX_CHART_LOOPS.
inline constexpr std::size_t MAX_CHART_YARNS = 64;
/// The most stitches one cable or twist may cross.
inline constexpr int MAX_CABLE_STITCHES = 64;

/// Which side of the fabric a float lies on.
enum class FloatSide : std::uint8_t {
  BACK,  ///< behind the stitches it passes: on the wrong side
  FRONT  ///< in front of them: on the right side
};

/// A MISS step of a yarn (the yarn passing a stitch without making a loop), with the side
/// of the fabric the float lies on (the graph's YarnStep has no place for it).
struct ChartFloat {
  int yarn = -1;
  std::size_t step = 0;  ///< index in the yarn's steps
  FloatSide side = FloatSide::BACK;
};

/// An increase made from the bar between two stitches (m1l, m1r): the NEW loop `loop` is
/// pulled through the yarn between `left` and `right` (the top loops of the stitches on
/// either side, as seen from the front), which the graph cannot name as a parent.
struct ChartIncrease {
  LoopId loop = NO_LOOP;
  LoopId left = NO_LOOP, right = NO_LOOP;
  bool leans_left = true;  ///< m1l; false: m1r
};

/// A chart's knit graph and what the graph has no place for.
struct ChartResult {
  KnitGraph graph;  ///< finished
  bool in_the_round = false;
  bool worked_cells = false;  ///< `cells: worked`
  int rows = 0;               ///< chart rows (row 1 … rows)
  int columns = 0;            ///< grid columns
  /// row_line[r]: the text line of row r (row_line[0] = 0, the cast-on)
  std::vector<int> row_line;
  /// right_side[r]: row r is worked from the right side ([0]: the cast-on, true)
  std::vector<bool> right_side;
  /// stitches[r]: live stitches after row r (stitches[0]: cast on)
  std::vector<int> stitches;
  /// the cell symbols used (normalised: "k2tog", "c4f", "cast-on"), each once
  std::vector<std::string> symbols;
  /// per loop: the index in `symbols` of the cell that made it
  std::vector<std::uint32_t> loop_symbol;
  /// the cell symbol that made loop `id`
  const std::string& symbol_of(LoopId id) const { return symbols[loop_symbol[id]]; }
  std::vector<LoopId> cast_on;
  /// loops pulled through their parents' back legs (ktbl, ptbl): the parents' legs cross
  std::vector<LoopId> twisted;
  std::vector<ChartIncrease> increases;
  std::vector<ChartFloat> floats;
  /// last loops of bind-offs that end a row: the cut yarn's tail is pulled through them
  /// (check() reports them free; they do not unravel)
  std::vector<LoopId> fastened_off;
  /// the stitches on the needle at the end, left to right, each its stack of loops
  /// (bottom first: a tucked or wrapped stitch holds two)
  std::vector<std::vector<LoopId>> live;
  /// short rows: rows that leave stitches unworked at an end (they turn before it, or
  /// start where the row below turned)
  std::vector<int> short_rows;
};

/// Builds the knit graph of chart `text` (the format above); `source_name` names it in
/// messages. Throws std::invalid_argument on a chart that cannot be knitted.
ChartResult read_chart_graph(std::string_view text, const std::string& source_name);

/// The graph of a k/p pattern's rows (knit::Pattern::rows: rows[0] the bottom row, each
/// a string of 'k' and 'p' as seen from the front, all of one length), knit flat: the
/// built-in patterns through the chart path (the k/p words are chart cells). Throws
/// std::invalid_argument as read_chart_graph does (LINE counts the rows from the top).
ChartResult kp_rows_graph(const std::vector<std::string>& rows, const std::string& source_name);

/// Reads the chart at `path` (a regular file of at most MAX_CHART_TEXT_BYTES) and builds
/// its graph; throws std::invalid_argument naming the path.
ChartResult load_chart_graph(const std::string& path);

}  // namespace knit::graph
