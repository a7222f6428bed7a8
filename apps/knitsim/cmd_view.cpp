// knitsim view STATE|DIR --out page.html: a run in the browser (src/knit/present/viewer.hpp)
#include <filesystem>
#include <iostream>
#include <stdexcept>

#include "commands.hpp"
#include "common.hpp"
#include "knit/io/state_file.hpp"
#include "knit/io/states.hpp"
#include "knit/present/viewer.hpp"
#include "knit/util/atomic_file.hpp"

namespace knitsim {
namespace fs = std::filesystem;

namespace {

struct ViewArgs {
  std::string input, out, title, scene;
  bool no_objects = false;
  int every = 1;
  knit::ViewerOptions viewer;
};

void run_view(ViewArgs a) {
  const std::string ext = fs::path(a.out).extension().string();
  if (ext != ".html" && ext != ".htm")
    throw std::invalid_argument("--out " + a.out + ": the viewer is a web page; name it .html");
  std::vector<knit::StateFile> frames;
  std::vector<double> times;
  if (fs::is_directory(a.input)) {
    const auto files = knit::list_state_files(a.input);
    for (size_t k = 0; k < files.size(); ++k)
      if (k % static_cast<size_t>(a.every) == 0 || k + 1 == files.size()) {
        frames.push_back(knit::read_state_file(files[k]));
        times.push_back(frames.back().state.time);
      }
  } else {
    frames.push_back(knit::load_state(a.input));
    times.push_back(frames.back().state.time);
  }
  a.viewer.objects = objects_for(a.input, a.scene, a.no_objects);
  a.viewer.title = a.title.empty() ? fs::path(a.input).filename().string() : a.title;
  if (a.viewer.title.empty()) a.viewer.title = "knitsim";
  knit::write_file_atomic(a.out, knit::viewer_html(frames, times, a.viewer));
  std::cout << "wrote " << a.out << " (" << frames.size()
            << (frames.size() == 1 ? " frame" : " frames") << "; open it in a web browser)\n";
}

}  // namespace

void register_view(CLI::App& app) {
  auto args = std::make_shared<ViewArgs>();
  CLI::App* sub = app.add_subcommand(
      "view", "write a web page that plays a run's frames as yarn tubes (orbit, time slider)");
  add_required_path(sub, "input", args->input, "a run's directory (its frames) or one state file")
      ->check(existing_path());
  add_out_option(sub, args->out, "the page (.html, self-contained: opens offline)");
  add_integer(sub, "--every", args->every, "show every Nth frame (and the last)", 1, 1000000,
              "count");
  add_text(sub, "--title", args->title, "shown on the page", "text", "the input's name");
  add_integer(sub, "--samples", args->viewer.samples_per_segment,
              "points along each spline segment", 1, 64, "count per segment");
  add_integer(sub, "--sides", args->viewer.sides, "vertices around the tube", 3, 64, "count");
  add_path(sub, "--scene", args->scene, "draw this scene's objects with the yarn",
           "the scene a simulation's summary.json beside the input names")
      ->check(existing_file());
  sub->add_flag("--no-objects", args->no_objects, "draw the yarn alone");
  sub->callback([args] { run_view(*args); });
}

const bool view_added = add_command(80, register_view);

}  // namespace knitsim
