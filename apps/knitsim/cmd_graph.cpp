// knitsim graph PROGRAM.k|CHART.chart [--loops] [--out FILE.json]: runs a knitout program
// on the machine model, or reads a hand-knitting chart, and prints its knit graph's summary
// as JSON (the library's knit_graph_json, src/knit/pattern/graph_summary.hpp; docs/knit-graph.md).
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "common.hpp"
#include "knit/pattern/graph_summary.hpp"
#include "knit/util/atomic_file.hpp"

namespace knitsim {

void register_graph(CLI::App& app) {
  struct Opts {
    std::string program, out;
    bool loops = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand(
      "graph",
      "print the knit graph of a knitout program (run on the machine model) or a chart, as JSON");
  add_required_path(
      cmd, "program", o->program,
      "knitout program (.k, .knitout) or hand-knitting chart (.chart, docs/charts.md)")
      ->check(existing_file());
  cmd->add_flag("--loops", o->loops, "list every loop (its needle, course, kind, face, parents)");
  add_out_option(cmd, o->out, "write the JSON to this file", "standard output");
  cmd->callback([o]() {
    const std::string text = knit::knit_graph_json(o->program, o->loops).dump(2) + "\n";
    if (o->out.empty())
      std::cout << text;
    else
      knit::write_file_atomic(o->out, text);
  });
}

const bool graph_added = add_command(75, register_graph);

}  // namespace knitsim
