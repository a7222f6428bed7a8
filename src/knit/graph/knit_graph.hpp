#pragma once
// The knit graph: the topology of a knitted piece, independent of any geometry.
//
// Nodes are loops. Each loop was made by one yarn (a carrier's piece of yarn, from the
// instruction that brought it in to the one that took it out) on one needle of one bed, in
// one pass, and it was pulled through an ordered list of parent loops (none for a tuck or
// a new loop on an empty needle; two or three for a decrease). Loops that were carried
// across each other by transfers under racking (cables, twists) are recorded as crossings,
// each naming the loop that passes in front. Each yarn keeps the sequence of its steps —
// the loops it made and the needles it was moved past (misses) — from where it comes in to
// where it goes out; the yarn between two consecutive steps is a float.
//
// The graph is built by front ends (the knitout interpreter, src/knit/graph/
// knitout_machine.hpp; charts later) through add_yarn / add_loop / add_miss / drop_loop /
// add_crossing / end_yarn, then finish(). A layout reads it: yarns() in order, each
// yarn's steps(), and per loop its bed, needle, course, parents() and face.
//
// This layer depends on the standard library only.
#include <cstdint>
#include <span>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace knit::graph {

/// A loop's index in KnitGraph::loops(); loops are numbered in the order they were made.
using LoopId = std::uint32_t;
inline constexpr LoopId NO_LOOP = ~LoopId{0};

/// The bed a loop was made on or is held by. Sliders (knitout's fs, bs) hold loops during
/// transfers only; no loop is made on them.
enum class Bed : std::uint8_t { FRONT, BACK, FRONT_SLIDER, BACK_SLIDER };

/// Whether `bed` is on the front side of the machine (the front bed or its sliders).
constexpr bool is_front_side(Bed bed) {
  return bed == Bed::FRONT || bed == Bed::FRONT_SLIDER;
}

/// How a loop was made.
enum class LoopKind : std::uint8_t {
  KNIT,   ///< pulled through the loops on its needle, which it replaces there (1+ parents)
  TUCK,   ///< laid onto a needle that holds loops, beside them; pulled through none
  SPLIT,  ///< pulled through the loops on its needle, which move to the opposite needle
  NEW,    ///< made on an empty needle (a cast-on, a yarn-over, an increase): no parents
};

/// Which side of a stitch shows as seen from the front of the machine: a loop pulled
/// towards the front bed shows its knit side (a V), one pulled towards the back bed its
/// purl side (a bump).
enum class Face : std::uint8_t { KNIT, PURL };

/// A carriage direction: towards higher needle numbers (PLUS) or lower ones (MINUS).
enum class Direction : std::int8_t { MINUS = -1, NONE = 0, PLUS = 1 };

/// What became of a loop at the end of the program.
enum class LoopEnd : std::uint8_t {
  LIVE,     ///< still on a needle when the program ended
  DROPPED,  ///< dropped off its needle (by drop, or by a knit without yarn)
  CONSUMED  ///< pulled through by a knit: it is held by that child and off the needles
};

struct Loop {
  LoopId id = NO_LOOP;
  int yarn = -1;  ///< index in KnitGraph::yarns()
  Bed bed = Bed::FRONT;
  int needle = 0;  ///< needle number on `bed` where the loop was made
  int pass = 0;    ///< the program's loop-making pass (see KnitGraph::passes)
  int course = 0;  ///< its yarn's pass: how many times the yarn turned before it
  LoopKind kind = LoopKind::KNIT;
  /// made by a tuck (knitout's tuck, a chart's tuck): a NEW loop a tuck made is a cast-on's
  /// or an increase's, one a knit made on an empty needle a stitch of its own
  bool tucked = false;
  Face face = Face::KNIT;
  Direction direction = Direction::NONE;  ///< the carriage direction it was formed in
  int line = 0;                           ///< source line of the instruction that made it
  int stitch_setting = -1;  ///< index in KnitGraph::stitch_settings(), -1: none was set
  LoopEnd end = LoopEnd::LIVE;
  int end_line = 0;  ///< the line that dropped or consumed it (0 for LIVE)
  std::uint32_t parent_begin = 0, parent_count = 0;  ///< in KnitGraph::parents
  std::uint32_t child_begin = 0, child_count = 0;    ///< in KnitGraph::children (finish)
};

/// One step of a yarn: a loop it made, or a needle it was moved past without making one.
struct YarnStep {
  enum Kind : std::uint8_t { LOOP, MISS };
  Kind kind = LOOP;
  LoopId loop = NO_LOOP;  ///< the loop (LOOP steps)
  Bed bed = Bed::FRONT;
  int needle = 0;
  Direction direction = Direction::NONE;
  int line = 0;
};

/// A piece of yarn: one carrier from the instruction that brought it in to the one that
/// took it out (a carrier brought in again later gives a new Yarn).
struct Yarn {
  std::string carrier;  ///< the carrier's name in the program
  int in_line = 0;      ///< the in/inhook line
  int out_line = 0;     ///< the out/outhook line; 0: still in when the program ended
  bool hook = false;    ///< brought in with the yarn-inserting hook (inhook)
  std::vector<YarnStep> steps;
};

/// Two loops carried across each other by racking, so that their order across the beds is
/// the reverse of the order of the needles they were made on (a cable, a twist): the yarn
/// of `front` passes in front of (nearer the front of the machine than) that of `back`.
struct Crossing {
  LoopId front = NO_LOOP;
  LoopId back = NO_LOOP;
  int line = 0;  ///< the rack instruction that carried them across
};

/// A loop-length setting (knitout's `stitch L T` or an extension such as
/// `x-stitch-number N`), as written; loops name the one in force when they were made.
struct StitchSetting {
  std::string op;  ///< "stitch", "x-stitch-number", …
  double value = 0, value2 = 0;
  int line = 0;
};

/// What KnitGraph::check found.
struct GraphCheck {
  /// loops held by no loop and still on a needle at the end (an unsecured edge)
  std::vector<LoopId> free_live;
  /// loops dropped while held by no loop: they would ladder (each loop's end_line names
  /// the drop)
  std::vector<LoopId> ladders;
  /// broken invariants of the graph itself (a yarn out of order, a parent made after its
  /// child, …): empty for a graph a front end built correctly
  std::vector<std::string> problems;
  bool ok() const { return problems.empty(); }
};

class KnitGraph {
 public:
  // ---- building (front ends) ----

  /// Reserves room for `loops` loops (and as many parents and yarn steps).
  void reserve(std::size_t loops);
  /// Starts a new piece of yarn for `carrier`, brought in at `in_line`; returns its index.
  int add_yarn(const std::string& carrier, int in_line, bool hook);
  /// Ends yarn `yarn` at `out_line` (the out/outhook instruction).
  void end_yarn(int yarn, int out_line);

  /// A new loop made by `yarn`, pulled through `parents` (bottom of the needle's stack
  /// first: the last parent lies on top); its id is the next one. `loop.yarn` must name a
  /// yarn that is in; id, parents, children and end are filled in here.
  LoopId add_loop(Loop loop, std::span<const LoopId> parents);
  /// `yarn` moved past `needle` without making a loop (knitout's miss).
  void add_miss(int yarn, Bed bed, int needle, Direction direction, int line);
  /// Marks `loop` consumed by a knit at `line` (it has just become a parent of a knit).
  void consume_loop(LoopId loop, int line);
  /// Marks `loop` dropped off its needle at `line`.
  void drop_loop(LoopId loop, int line);
  /// Records that `front` and `back` were carried across each other at `line`, `front`
  /// passing in front (replacing what was recorded of the two).
  void add_crossing(LoopId front, LoopId back, int line);
  /// Records that loops `a` and `b` were carried back and no longer cross.
  void remove_crossing(LoopId a, LoopId b);
  /// Adds a stitch setting; returns its index.
  int add_stitch_setting(StitchSetting setting);
  /// Builds the children lists and closes the graph for reading.
  void finish();

  // ---- reading ----

  const std::vector<Loop>& loops() const { return m_loops; }
  const Loop& loop(LoopId id) const { return m_loops[id]; }
  std::size_t num_loops() const { return m_loops.size(); }
  /// The loops `id` was pulled through, bottom of the needle's stack first.
  std::span<const LoopId> parents(LoopId id) const;
  /// The loops pulled through `id`, in the order they were made (after finish()).
  std::span<const LoopId> children(LoopId id) const;
  const std::vector<Yarn>& yarns() const { return m_yarns; }
  /// Crossings in force at the end (loops carried back again do not cross), in the order made.
  std::vector<Crossing> crossings() const;
  const std::vector<StitchSetting>& stitch_settings() const { return m_settings; }
  /// The number of loop-making passes (Loop::pass runs from 0 to passes() - 1).
  int passes() const;
  /// Loops per kind, indexed by LoopKind.
  std::vector<std::size_t> count_by_kind() const;

  /// Checks the graph: every yarn continuous (its steps in the order made, each loop on
  /// the yarn that made it, once), every parent made before its child, and every loop
  /// held by a child, else reported as free (live at the end, or dropped: a ladder).
  GraphCheck check() const;

  /// Approximate memory the graph holds (bytes).
  std::size_t memory_bytes() const;

 private:
  std::vector<Loop> m_loops;
  std::vector<LoopId> m_parents;
  std::vector<LoopId> m_children;
  std::vector<Yarn> m_yarns;
  /// the crossings in force, by loop pair, with the order they were made in
  std::unordered_map<std::uint64_t, std::pair<std::uint64_t, Crossing>> m_crossing_of;
  std::uint64_t m_crossings_made = 0;
  std::vector<StitchSetting> m_settings;
  std::size_t m_step_reserve = 0;
  bool m_finished = false;
};

const char* bed_name(Bed bed);                 ///< "f", "b", "fs", "bs"
const char* kind_name(LoopKind kind);          ///< "knit", "tuck", "split", "new"
const char* face_name(Face face);              ///< "knit", "purl"
const char* end_name(LoopEnd end);             ///< "live", "dropped", "consumed"
std::string needle_name(Bed bed, int needle);  ///< "f12", "bs-3"

}  // namespace knit::graph
