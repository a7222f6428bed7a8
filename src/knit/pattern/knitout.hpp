#pragma once
// Knitting-machine programs as input: knitout (".k", textiles-lab's format for V-bed
// machines), read into the chart and size the generator knits.
//
// What is read — a rectangular piece knitted by one carrier, flat or in the round:
//   ;!knitout-N      first line (required); other ';' lines are comments and headers
//   in/inhook C, releasehook C, out/outhook C    the carrier (one only)
//   tuck D N C       cast-on: tucks on empty needles before the first stitch
//   knit D N C       a stitch on needle N (f12 front bed, b12 back bed) in direction D (+/-)
//   purl D N C       the loop pulled the other way (a purl as seen from that bed)
//   miss D N C       moves the carrier only
//   rack 0           (any other racking is refused)
// Flat: every needle index is used on one bed only; column c is the c-th needle from the
// left; a knit on the front bed (or a purl on the back) is 'k' as seen from the front, a
// knit on the back bed (or a purl on the front) is 'p'. In the round: needles used on both
// beds; the columns run around the tube, front needles left to right then back needles
// right to left, and a knit on either bed is 'k' seen from outside.
// Each row is one pass over every column (a round: the front pass then the back one), in
// order; every column ends with the same number of rows.
// Refused with the line and instruction named: transfers (xfer, split), racking, drops,
// tucks after the cast-on, sliders, several carriers, shaping (columns of different
// heights, short rows), and anything else.
#include <string>
#include <string_view>

#include "knit/graph/knitout_machine.hpp"
#include "knit/pattern/pattern.hpp"

namespace knit {

struct KnitoutPiece {
  Pattern pattern;  ///< the program's stitches, as seen from the front (or outside)
  bool in_the_round = false;
  int rows() const { return pattern.num_rows(); }
  int cols() const { return pattern.num_cols(); }
};

/// Reads a knitout program's text; throws std::invalid_argument naming `source_name`,
/// the line and the instruction on anything it cannot knit.
KnitoutPiece parse_knitout(std::string_view text, const std::string& source_name);

/// The sheet of a program already run (`result` of graph::run_knitout on `text`): what
/// parse_knitout returns after running it.
KnitoutPiece knitout_sheet(const graph::KnitoutResult& result, std::string_view text,
                           const std::string& source_name);

/// Whether `name_or_path` names a knitout program: a path ending in ".k", or a regular
/// file of any other name whose first line is the knitout header ";!knitout-".
bool is_knitout_path(const std::string& name_or_path);

/// Reads the knitout program at `path` (at most MAX_CHART_BYTES).
KnitoutPiece load_knitout(const std::string& path);

}  // namespace knit
