// knitsim export STATE|DIR --format usd|obj|bcc|ply --out FILE
#include <filesystem>
#include <iostream>
#include <stdexcept>

#include "commands.hpp"
#include "common.hpp"
#include "knit/io/export.hpp"
#include "knit/io/states.hpp"

namespace knitsim {
namespace fs = std::filesystem;

namespace {

struct ExportArgs {
  std::string input, format, out;
  std::string scene;
  int samples = knit::EXPORT_SAMPLES_PER_SEGMENT;
  bool ascii = false, no_objects = false;
  std::vector<std::shared_ptr<const knit::SceneObject>> objects;
};

void write_one(const knit::StateFile& s, const ExportArgs& a, const std::string& out) {
  if (a.format == "obj") knit::export_obj(s, out, a.samples);
  if (a.format == "bcc") knit::export_bcc(s, out, a.samples);
  if (a.format == "ply") knit::export_ply(s, out, !a.ascii, a.samples);
  if (a.format == "usd") knit::export_usd({s}, {s.state.time}, out, a.objects);
}

void run_export(ExportArgs a) {
  if (a.format == "usd") a.objects = objects_for(a.input, a.scene, a.no_objects);
  if (!fs::is_directory(a.input)) {
    write_one(knit::load_state(a.input), a, a.out);
    std::cout << "wrote " << a.out << "\n";
    return;
  }
  const auto files = knit::list_state_files(a.input);
  if (a.format == "usd") {
    std::vector<knit::StateFile> frames;
    std::vector<double> times;
    for (const auto& f : files) {
      frames.push_back(knit::read_state_file(f));
      times.push_back(frames.back().state.time);
      if (frames.back().yarn_cp_counts != frames.front().yarn_cp_counts)
        throw std::runtime_error(f + ": yarn layout differs from " + files.front() +
                                 "; one USD file needs the same yarns in every state");
    }
    bool increasing = true;
    for (size_t i = 1; i < times.size(); ++i) increasing &= times[i] > times[i - 1];
    if (!increasing) {
      std::cerr << "knitsim: note: state times do not increase in file-name order; using the "
                   "frame index at 24 frames/s\n";
      for (size_t i = 0; i < times.size(); ++i) times[i] = static_cast<double>(i) / 24.0;
    }
    knit::export_usd(frames, times, a.out, a.objects);
    std::cout << "wrote " << a.out << " (" << frames.size() << " time samples)\n";
    return;
  }
  // other formats: one file per state, into the --out directory
  if (fs::exists(a.out) && !fs::is_directory(a.out))
    throw std::runtime_error("--out " + a.out + ": exporting a directory of states to " + a.format +
                             " writes one file per state; give a directory");
  fs::create_directories(a.out);
  for (const auto& f : files) {
    const std::string out = (fs::path(a.out) / fs::path(f).stem()).string() + "." + a.format;
    write_one(knit::read_state_file(f), a, out);
  }
  std::cout << "wrote " << files.size() << " " << a.format << " files to " << a.out << "\n";
}

}  // namespace

void register_export(CLI::App& app) {
  auto args = std::make_shared<ExportArgs>();
  CLI::App* sub = app.add_subcommand(
      "export", "export a state (.kstate, or .yarns/.bcc/.obj) or a directory of states");
  sub->add_option("input", args->input, "state file or directory of .kstate files")
      ->required()
      ->check(CLI::ExistingPath);
  sub->add_option("--format,-f", args->format, "usd (exact curves), obj, bcc, ply (sampled)")
      ->required()
      ->check(CLI::IsMember({"usd", "obj", "bcc", "ply"}));
  sub->add_option("--out,-o", args->out, "output file (a directory for several obj/bcc/ply)")
      ->required();
  sub->add_option("--samples", args->samples, "polyline samples per spline segment (obj, bcc, ply)")
      ->check(CLI::Range(1, 1000));
  sub->add_flag("--ascii", args->ascii, "ascii PLY instead of binary");
  sub->add_option("--scene", args->scene,
                  "usd: write this scene's objects beside the yarn (default: the scene a "
                  "simulation's summary.json beside the input names)")
      ->check(CLI::ExistingFile);
  sub->add_flag("--no-objects", args->no_objects, "usd: the yarn alone");
  sub->callback([args] { run_export(*args); });
}

}  // namespace knitsim
