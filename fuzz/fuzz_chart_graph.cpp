// libFuzzer target: the hand-knitting chart front end (read_chart_graph), which reads a
// chart with real stitches and builds its knit graph.
// std::invalid_argument is a clean refusal; crashes, sanitizer reports, hangs and a graph
// that breaks the front end's promises are bugs: the graph passes its own checks with no
// ladder, the loops no loop holds are exactly the stitches left on the needle and the
// fastened-off ends of bind-offs, every parent was made before its child, crossings name
// two different loops, each recorded float is a miss step of its yarn, and the stitch
// counts per row end at the stitches left.
#include <cstddef>
#include <cstdint>
#include <set>
#include <stdexcept>
#include <string_view>

#include "knit/graph/chart.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  namespace g = knit::graph;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const g::ChartResult r = g::read_chart_graph(text, "fuzz.chart");
    const g::KnitGraph& graph = r.graph;
    const g::GraphCheck c = graph.check();
    if (!c.ok() || !c.ladders.empty()) __builtin_trap();
    std::set<g::LoopId> expected(r.fastened_off.begin(), r.fastened_off.end());
    for (const auto& stack : r.live)
      for (g::LoopId l : stack) expected.insert(l);
    if (std::set<g::LoopId>(c.free_live.begin(), c.free_live.end()) != expected) __builtin_trap();
    if (r.loop_symbol.size() != graph.num_loops()) __builtin_trap();
    for (std::uint32_t k : r.loop_symbol)
      if (k >= r.symbols.size()) __builtin_trap();
    for (const g::Loop& l : graph.loops()) {
      if (l.yarn < 0 || static_cast<std::size_t>(l.yarn) >= graph.yarns().size()) __builtin_trap();
      for (g::LoopId p : graph.parents(l.id))
        if (p >= l.id) __builtin_trap();
    }
    for (const g::Crossing& x : graph.crossings())
      if (x.front == x.back || x.front >= graph.num_loops() || x.back >= graph.num_loops())
        __builtin_trap();
    for (const g::ChartFloat& f : r.floats) {
      if (f.yarn < 0 || static_cast<std::size_t>(f.yarn) >= graph.yarns().size()) __builtin_trap();
      const auto& steps = graph.yarns()[static_cast<std::size_t>(f.yarn)].steps;
      if (f.step >= steps.size() || steps[f.step].kind != g::YarnStep::MISS) __builtin_trap();
    }
    if (r.stitches.size() != static_cast<std::size_t>(r.rows) + 1 ||
        static_cast<std::size_t>(r.stitches.back()) != r.live.size())
      __builtin_trap();
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
