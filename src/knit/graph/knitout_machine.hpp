#pragma once
// A knitout interpreter: runs a knitout program (textiles-lab's "The Knitout (.k) File
// Format", knitout-2; ".k" and ".knitout" are the same format) on a model of a V-bed
// machine and builds the knit graph of what it knits.
//
// The machine: a front and a back bed of needles (and their sliders, fs/bs, which hold
// loops during transfers), each needle holding a stack of loops (the oldest at the
// bottom); the racking R (front needle F faces back needle F - R; fractional values such
// as 0.25 for all-needle knitting align no needles for transfers); the carriers, each in
// or out, with the inserting hook; the current loop-length setting.
//
// What each instruction does to the graph (D: + or -, N/N2: needles such as f12, b-3,
// fs4; CS: carriers):
//   knit D N CS     one new loop per carrier, pulled through the loops on N (its parents,
//                   bottom of the stack first), which leave the needle; on an empty needle
//                   a NEW loop. With no carriers: drop.
//   purl D N CS     (an older opcode, read with a note) a knit whose loop is pulled the
//                   other way: its face is the opposite of a knit's on that bed
//   tuck D N CS     new loop(s) laid on top of the loops on N (TUCK; NEW on an empty
//                   needle). With no carriers: amiss.
//   split D N N2 CS a loop pulled through the loops on N, which move to N2 (on top of what
//                   N2 holds). With no carriers: xfer.
//   xfer N N2       the loops on N move to N2, on top of what N2 holds; N and N2 on
//                   opposite beds and aligned by the racking
//   drop N          the loops on N leave it (a loop no child holds would ladder)
//   amiss N         nothing is made
//   miss D N CS     the carriers move past N: a step on their yarns, no loop
//   rack R          the back bed moves; loops carried across loops on the other bed
//                   cross, the front bed's loop in front
//   in/inhook CS, out/outhook CS, releasehook CS    carriers in and out (a yarn each
//                   from in to out), the hook
//   stitch L T, x-stitch-number N    the loop-length setting of the loops that follow
//   pause, other x- extensions        accepted (extensions with a note)
// Headers (";;Name: value" lines before the first instruction): Carriers (when given,
// the only carrier names accepted), Width (the bed's needles: a program whose needles
// span more is refused), Machine, Gauge, Position, Yarn-C, X-… (kept).
//
// Refused with std::invalid_argument "SOURCE:LINE: 'INSTRUCTION': what was expected": bad
// syntax, an unknown opcode, a carrier not in (or not in the Carriers header), a carrier
// brought in twice, a releasehook without an inhook, a transfer between needles on the
// same bed or not aligned by the racking, stitches on sliders, a needle beyond the
// interpreter's range (|N| <= MAX_NEEDLE) or the bed's width, a racking beyond MAX_RACK,
// more than MAX_LOOPS loops or MAX_LOOPS_PER_NEEDLE on a needle, racking that carries more
// than MAX_RACK_PAIRS loop pairs past each other.
#include <cstddef>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "knit/graph/knit_graph.hpp"

namespace knit::graph {

/// The largest knitout program read (bytes): 64 MB. A program's graph takes about 8 times
/// its size in memory (about 100 bytes per loop for a 12-byte instruction line), so this
/// bounds it near 600 MB.
inline constexpr std::size_t MAX_KNITOUT_BYTES = 64ull << 20;
/// Needle numbers accepted: -MAX_NEEDLE … MAX_NEEDLE (no machine is wider).
inline constexpr int MAX_NEEDLE = 10000;
/// The largest racking accepted, in needles (either way); machines rack a few inches.
inline constexpr double MAX_RACK = 32;
/// The most loops one needle may hold at once (a hook holds a few: a decrease stacks 2-3,
/// tucks a few more).
inline constexpr std::size_t MAX_LOOPS_PER_NEEDLE = 32;
/// The most loop pairs the racking may carry past each other over a whole program (each
/// rack looks at the pairs its back-bed loops sweep past).
inline constexpr std::size_t MAX_RACK_PAIRS = std::size_t{1} << 28;
/// The most loops a program may make.
inline constexpr std::size_t MAX_LOOPS = 8u << 20;

/// A remark on something accepted but not interpreted (an extension, an old opcode).
struct KnitoutNote {
  int line = 0;   ///< its first occurrence
  int count = 0;  ///< how many lines it applies to
  std::string text;
};

/// The result of running a program.
struct KnitoutResult {
  KnitGraph graph;                             ///< finished
  std::map<std::string, std::string> headers;  ///< ";;Name: value" header lines
  std::vector<KnitoutNote> notes;
  int version = 0;               ///< N of ";!knitout-N"
  int lines = 0;                 ///< lines read
  std::size_t instructions = 0;  ///< instruction lines (not comments or blank)
  double final_racking = 0;
};

/// Runs the knitout program `text`; `source_name` names it in messages. Throws
/// std::invalid_argument on a program the machine would refuse (see above).
KnitoutResult run_knitout(std::string_view text, const std::string& source_name);

/// The text of the program at `path` (a regular file of at most MAX_KNITOUT_BYTES); throws
/// std::invalid_argument naming the path on a file that cannot be read.
std::string read_knitout_text(const std::string& path);

/// Reads the program at `path` (read_knitout_text) and runs it; throws
/// std::invalid_argument naming the path on a file that cannot be read or run.
KnitoutResult load_knitout_graph(const std::string& path);

}  // namespace knit::graph
