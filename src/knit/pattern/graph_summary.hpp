#pragma once
// The knit graph of a knitout program or a hand-knitting chart as JSON: what `knitsim graph`
// prints and Python's knit_graph() returns (docs/knit-graph.md). The loops by kind, face and
// bed, the yarns (carrier, in and out lines, loops, misses, courses), passes, free loops
// (live at the end, or dropped: ladders, each with the line that made it and the one that
// dropped it), crossings, stitch settings, the checks' problems, the interpreter's notes,
// and for a program what `relax` lays of it (`sheet`: its rows and columns, or why not);
// with `loops` every loop too.
#include <nlohmann/json.hpp>
#include <string>

namespace knit {

/// Whether `path` names a chart (.chart, any case) rather than a knitout program.
bool is_chart_path(const std::string& path);

/// Runs the program (or reads the chart) at `path` and returns its graph's summary. Throws
/// std::invalid_argument naming the path, line and instruction on a program the machine
/// refuses or a chart that cannot be read.
nlohmann::ordered_json knit_graph_json(const std::string& path, bool loops = false);

}  // namespace knit
