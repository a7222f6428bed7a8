// libFuzzer target: the knitout interpreter (run_knitout), which runs a program on the
// machine model and builds its knit graph, and the sheet reader (knitout_sheet) that reads
// the rows `relax` lays from that graph.
// std::invalid_argument is a clean refusal; crashes, sanitizer reports, hangs and a graph
// that breaks the interpreter's promises are bugs: a graph the interpreter built passes
// the graph's own checks, every loop's parents were made before it and lie on its yarn's
// machine (ids in range), its crossings name two different loops, and the check's free
// loops are loops the graph holds; a sheet read from it has no more stitches than the graph
// has loops, and a yarn for each row, every yarn knitting a row.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "knit/graph/knitout_machine.hpp"
#include "knit/pattern/knitout.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const knit::graph::KnitoutResult r = knit::graph::run_knitout(text, "fuzz.k");
    const knit::graph::KnitGraph& g = r.graph;
    const knit::graph::GraphCheck c = g.check();
    if (!c.ok()) __builtin_trap();
    std::size_t parents = 0, children = 0;
    for (const knit::graph::Loop& l : g.loops()) {
      if (l.yarn < 0 || static_cast<std::size_t>(l.yarn) >= g.yarns().size()) __builtin_trap();
      for (knit::graph::LoopId p : g.parents(l.id))
        if (p >= l.id) __builtin_trap();
      parents += g.parents(l.id).size();
      children += g.children(l.id).size();
    }
    if (parents != children) __builtin_trap();
    for (const knit::graph::Crossing& x : g.crossings())
      if (x.front == x.back || x.front >= g.num_loops() || x.back >= g.num_loops())
        __builtin_trap();
    for (knit::graph::LoopId l : c.free_live)
      if (l >= g.num_loops() || g.loop(l).end != knit::graph::LoopEnd::LIVE) __builtin_trap();
    for (knit::graph::LoopId l : c.ladders)
      if (l >= g.num_loops() || g.loop(l).end != knit::graph::LoopEnd::DROPPED) __builtin_trap();
    try {
      const knit::KnitoutPiece p = knit::knitout_sheet(r, text, "fuzz.k");
      const std::size_t stitches = static_cast<std::size_t>(p.rows()) * p.cols();
      if (p.rows() < 1 || p.cols() < 1 || stitches > g.num_loops()) __builtin_trap();
      const auto& row_yarn = p.pattern.row_yarn;
      if (!row_yarn.empty()) {
        if (row_yarn.size() != static_cast<std::size_t>(p.rows()) ||
            p.pattern.row_leftward.size() != row_yarn.size() || p.in_the_round)
          __builtin_trap();
        std::vector<char> knits(row_yarn.size(), 0);
        for (int y : row_yarn) {
          if (y < 0 || static_cast<std::size_t>(y) >= row_yarn.size()) __builtin_trap();
          knits[y] = 1;
        }
        for (int y = 0; y < p.pattern.num_yarns(); ++y)
          if (!knits[y]) __builtin_trap();
      }
    } catch (const std::invalid_argument&) {
    }
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
