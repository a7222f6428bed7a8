// knitsim: yarn-level simulation of knitted cloth. A thin front end over knit::knit;
// each subcommand lives in its own cmd_*.cpp file.
#include <exception>
#include <iostream>
#include <new>
#include <string>

#include "commands.hpp"
#include "common.hpp"
#include "knit/io/input_file.hpp"
#include "knit/io/run_dir.hpp"
#include "knit/solver/interrupt.hpp"

int main(int argc, char** argv) {
  knitsim::set_command_line(argc, argv);
  CLI::App app{"knitsim " KNIT_VERSION " — yarn-level simulation of knitted cloth"};
  app.set_version_flag("--version", "knitsim " KNIT_VERSION);
  app.require_subcommand(1);
  // before the subcommands, which take the formatter over
  app.formatter(knitsim::help_formatter());
  knitsim::register_simulate(app);
  knitsim::register_relax(app);
  knitsim::register_export(app);
  knitsim::register_render(app);
  knitsim::register_plot(app);
  knitsim::register_stretch(app);
  knitsim::register_mesh(app);
  knitsim::register_view(app);
  knitsim::register_graph(app);
  knitsim::register_version(app);
  app.footer(knitsim::help_footer());
  for (CLI::App* sub : app.get_subcommands({})) sub->footer(knitsim::help_footer());
  // an output named "" would be no output at all: refused by every command alike
  const CLI::Validator named(
      [](std::string& s) {
        return s.empty() ? std::string("the name is empty; give a file or directory") : "";
      },
      "", "not empty");
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; }))
    if (CLI::Option* out = sub->get_option_no_throw("--out")) out->check(named);
  // the first SIGINT/SIGTERM ends a run cleanly after its current step (state and summary
  // written); a second one ends the process at once. Installed until the process ends: a
  // signal that comes after a finished run (while it exits) leaves its exit status 0
  knit::handle_interrupts_until_exit();
  // the run directories a command opens stay locked until it ends: its own outputs after
  // the recipe's (a stretch's relaxed.kstate) are named in the directory's marker too
  const knit::RunDirectoryScope run_directories;
  // an unknown command is named (CLI11 says only that a subcommand is required)
  if (argc > 1 && argv[1][0] != '-') {
    std::string names;
    bool known = false;
    for (const CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
      known = known || sub->get_name() == argv[1];
      names += (names.empty() ? "" : ", ") + sub->get_name();
    }
    if (!known) {
      std::cerr << "knitsim: error: unknown command '" << knit::printable(argv[1]) << "' (one of "
                << names << "; knitsim --help says more)\n";
      return knitsim::EXIT_ERROR;  // a command line refused (docs/cli.md, "Exit codes")
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version end here too (0); every command line refused exits as any
    // other refused input does (docs/cli.md, "Exit codes")
    return app.exit(e) == 0 ? knitsim::EXIT_OK : knitsim::EXIT_ERROR;
  } catch (const knitsim::RunFailed&) {
    return knitsim::EXIT_RUN_FAILED;
  } catch (const knitsim::RunInterrupted& e) {
    return 128 + e.signal;
  } catch (const std::bad_alloc&) {
    std::cerr << "knitsim: error: out of memory (the request is too large for this machine)\n";
    return knitsim::EXIT_ERROR;
  } catch (const std::exception& e) {
    std::cerr << "knitsim: error: " << e.what() << "\n";
    return knitsim::EXIT_ERROR;
  }
  return knitsim::EXIT_OK;
}
