// knitsim: yarn-level simulation of knitted cloth. A thin front end over knit::knit;
// each subcommand lives in its own cmd_*.cpp file.
#include <exception>
#include <iostream>

#include "commands.hpp"
#include "common.hpp"

int main(int argc, char** argv) {
  CLI::App app{"knitsim " KNIT_VERSION " — yarn-level simulation of knitted cloth"};
  app.require_subcommand(1);
  knitsim::register_simulate(app);
  knitsim::register_relax(app);
  knitsim::register_export(app);
  knitsim::register_render(app);
  knitsim::register_plot(app);
  knitsim::register_stretch(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const knitsim::RunFailed&) {
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "knitsim: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
