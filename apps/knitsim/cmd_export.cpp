// knitsim export STATE|DIR --format FORMAT --out FILE (the formats: knit/io/formats.hpp)
#include <filesystem>
#include <iostream>
#include <stdexcept>

#include "commands.hpp"
#include "common.hpp"
#include "knit/io/export.hpp"
#include "knit/io/formats.hpp"
#include "knit/io/states.hpp"
#include "knit/io/tube_mesh.hpp"

namespace knitsim {
namespace fs = std::filesystem;

namespace {

struct ExportArgs {
  std::string input, format, out;
  std::string scene;
  int samples = knit::EXPORT_SAMPLES_PER_SEGMENT;
  int sides = knit::TUBE_SIDES;
  bool ascii = false, no_objects = false;
  bool y_up = false, metres = false;
  std::vector<std::shared_ptr<const knit::SceneObject>> objects;
};

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// an output named for another format than the one written is refused: a reader would
// misread it
void check_extension(const ExportArgs& a) {
  const std::string ext = lower(fs::path(a.out).extension().string());
  const std::string want = knit::export_extension(a.format);
  if (a.format == "usd" && (ext == ".usdc" || ext == ".usdz"))
    throw std::invalid_argument("--out " + a.out +
                                ": knitsim writes USD as text; name it .usda (or .usd); " + ext +
                                " is USD's binary " + (ext == ".usdc" ? "crate" : "zip package") +
                                " format, which it cannot write");
  if (ext == want || (a.format == "usd" && ext == ".usd")) return;
  throw std::invalid_argument("--out " + a.out + ": the " + a.format + " format writes a " + want +
                              " file; name the output so (got " +
                              (ext.empty() ? "no extension" : ext) + ")");
}

// for tools that assume Y up or metres: (x, y, z) → (x, z, −y), and cm → m
knit::StateFile in_axes(knit::StateFile s, const ExportArgs& a) {
  const double scale = a.metres ? 0.01 : 1.0;
  for (int k = 0; k < s.num_cp(); ++k)
    for (Eigen::VectorXd* x : {&s.state.q, &s.state.v}) {
      const Eigen::Vector3d p = x->segment<3>(3 * k);
      x->segment<3>(3 * k) = scale * (a.y_up ? Eigen::Vector3d(p.x(), p.z(), -p.y()) : p);
    }
  for (double& r : s.yarn_radius) r *= scale;
  return s;
}

void write_one(const knit::StateFile& state, const ExportArgs& a, const std::string& out) {
  const knit::StateFile s = a.y_up || a.metres ? in_axes(state, a) : state;
  knit::ExportOptions o;
  o.samples = a.samples;
  o.sides = a.sides;
  o.binary_ply = !a.ascii;
  o.objects = a.objects;
  knit::export_state(s, a.format, out, o);
}

void run_export(ExportArgs a) {
  if ((a.y_up || a.metres) && (a.format == "usd" || a.format == "glb"))
    throw std::invalid_argument(
        "--y-up and --metres are for obj, ply, bcc, vtp and the obj and "
        "ply meshes: " +
        a.format + " states its axes and units itself");
  if (a.format == "usd") a.objects = objects_for(a.input, a.scene, a.no_objects);
  if (!fs::is_directory(a.input) || a.format == "usd") check_extension(a);
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
    const std::string out =
        (fs::path(a.out) / fs::path(f).stem()).string() + knit::export_extension(a.format);
    write_one(knit::read_state_file(f), a, out);
  }
  std::cout << "wrote " << files.size() << " " << a.format << " files to " << a.out << "\n";
}

}  // namespace

void register_export(CLI::App& app) {
  auto args = std::make_shared<ExportArgs>();
  CLI::App* sub = app.add_subcommand(
      "export", "export a state (.kstate, or .yarns/.bcc/.obj) or a directory of states");
  add_required_path(sub, "input", args->input, "state file or directory of .kstate files")
      ->check(existing_path());
  add_choice(sub, "--format,-f", args->format, knit::export_format_list(), knit::export_formats(),
             "none (required)")
      ->required();
  add_out_option(sub, args->out, "output file (a directory for several obj/bcc/ply)");
  add_integer(sub, "--samples", args->samples,
              "polyline samples per spline segment (obj, bcc, ply, vtp)", 1, 1000,
              "count per segment");
  sub->add_flag("--ascii", args->ascii, "ascii PLY instead of binary");
  add_integer(sub, "--sides", args->sides, "tube meshes: vertices around the yarn", 3, 64, "count");
  add_path(sub, "--scene", args->scene, "usd: write this scene's objects beside the yarn",
           "the scene a simulation's summary.json beside the input names")
      ->check(existing_file());
  sub->add_flag("--no-objects", args->no_objects, "usd: the yarn alone");
  sub->add_flag("--y-up", args->y_up,
                "obj, ply, bcc, vtp and meshes: turn Z up into Y up, (x, y, z) → (x, z, −y), "
                "for tools that assume Y up (Blender's OBJ importer's default, Maya, Unity)");
  sub->add_flag("--metres", args->metres,
                "obj, ply, bcc, vtp and meshes: write metres instead of cm (USD says its unit, "
                "glb is always metres)");
  sub->callback([args] { run_export(*args); });
}

const bool export_added = add_command(30, register_export);

}  // namespace knitsim
