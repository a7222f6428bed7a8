// knitsim render STATE|DIR --out FILE.png|DIR [--size WxH] [--view front|back|side|iso]
//                [--color-rows] [--spp N] [--box X0,Y0,Z0,X1,Y1,Z1]
// knitsim render --compare A B C --out F.png [--labels a,b,c]
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <stdexcept>

#include "commands.hpp"
#include "common.hpp"
#include "knit/io/states.hpp"
#include "knit/present/render.hpp"
#include "knit/present/sequence.hpp"
#include "knit/util/process.hpp"
#include "knit/util/run_dir.hpp"

namespace knitsim {
namespace fs = std::filesystem;

namespace {

struct RenderArgs {
  // the renderer's own defaults
  std::string input, out,
      size = std::to_string(knit::RenderOptions{}.width) + "x" +
             std::to_string(knit::RenderOptions{}.height),
      view = "front", labels, scene;
  bool no_objects = false;
  std::vector<std::string> compare;
  bool color_rows = false, overwrite = false;
  int spp = knit::RenderOptions{}.spp, shadow_rays = knit::RenderOptions{}.shadow_rays,
      ao_rays = knit::RenderOptions{}.ao_rays;
  double fps = 0;  // real time
  bool no_scale_bar = false;
  std::vector<double> box;  // x0,y0,z0,x1,y1,z1 (cm): a close-up; empty: the whole knit
};

knit::RenderOptions options_from(const RenderArgs& a) {
  knit::RenderOptions o;
  int w = 0, h = 0;
  char tail = 0;
  if (std::sscanf(a.size.c_str(), "%dx%d%c", &w, &h, &tail) != 2 || w < 1 || h < 1 || w > 16384 ||
      h > 16384)
    throw std::runtime_error("--size " + a.size +
                             ": expected WxH with W and H from 1 to 16384, e.g. 1024x768");
  o.width = w;
  o.height = h;
  o.view = knit::parse_view(a.view);
  o.color_rows = a.color_rows;
  o.spp = a.spp;
  o.shadow_rays = a.shadow_rays;
  o.ao_rays = a.ao_rays;
  o.scale_bar = !a.no_scale_bar;
  if (!a.box.empty()) {
    const char* axis = "xyz";
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(a.box[k]) || !std::isfinite(a.box[k + 3]) || a.box[k] >= a.box[k + 3])
        throw std::runtime_error(std::string("--box: its ") + axis[k] + " range " +
                                 std::to_string(a.box[k]) + " to " + std::to_string(a.box[k + 3]) +
                                 " is empty; give X0,Y0,Z0,X1,Y1,Z1 (cm) with each lower corner "
                                 "below the upper one");
    o.frame = Eigen::AlignedBox3d(Eigen::Vector3d(a.box[0], a.box[1], a.box[2]),
                                  Eigen::Vector3d(a.box[3], a.box[4], a.box[5]));
  }
  return o;
}

void note_rows(const knit::StateFile& s, const RenderArgs& a, const std::string& name) {
  if (a.color_rows && s.stitch.empty())
    std::cerr << "knitsim: note: " << name
              << " has no stitch rows; --color-rows falls back to colours per yarn\n";
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::vector<std::string> split_labels(const std::string& s) {
  std::vector<std::string> out;
  if (s.empty()) return out;
  size_t pos = 0;
  while (true) {
    const size_t c = s.find(',', pos);
    out.push_back(s.substr(pos, c - pos));
    if (c == std::string::npos) break;
    pos = c + 1;
  }
  return out;
}

void render_compare(const RenderArgs& a, knit::RenderOptions o) {
  std::vector<knit::StateFile> states;
  std::vector<Eigen::AlignedBox3d> boxes;
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
  for (const auto& f : a.compare) {
    states.push_back(knit::load_state(f));
    note_rows(states.back(), a, f);
    boxes.push_back(knit::state_bounds(states.back()));
    size = size.cwiseMax(boxes.back().sizes());
  }
  std::vector<std::string> labels = split_labels(a.labels);
  if (!labels.empty() && labels.size() != a.compare.size())
    throw std::runtime_error("--labels: " + std::to_string(labels.size()) + " labels for " +
                             std::to_string(a.compare.size()) + " states");
  if (labels.empty())
    for (const auto& f : a.compare) labels.push_back(fs::path(f).stem().string());
  // one scale for every panel: each is framed on a box of the largest size, centred on
  // its own state
  std::vector<knit::Image> panels;
  for (size_t i = 0; i < states.size(); ++i) {
    const Eigen::Vector3d c = boxes[i].center();
    o.frame = Eigen::AlignedBox3d(c - size / 2, c + size / 2);
    panels.push_back(knit::render_state(states[i], o));
  }
  knit::write_png(knit::compose_side_by_side(panels, labels), a.out);
  std::cout << "wrote " << a.out << "\n";
}

void render_sequence(const RenderArgs& a, const knit::RenderOptions& o) {
  const auto files = knit::list_state_files(a.input);
  if (fs::exists(a.out) && !fs::is_directory(a.out))
    throw std::runtime_error("--out " + a.out +
                             ": rendering a directory of states writes numbered frames; give a "
                             "directory");
  // frames of an earlier sequence would end up in this one's movie
  const knit::RunDirectory held = knit::prepare_run_directory(a.out, a.overwrite);
  note_rows(knit::read_state_file(files.front()), a, files.front());
  const knit::SequenceResult r = knit::render_sequence(files, o, a.out, a.fps);
  std::cout << "wrote " << r.frames << " frames to " << a.out << " (" << r.seconds_per_frame
            << " s per frame";
  if (r.stride > 1) std::cout << "; one state in " << r.stride;
  std::cout << ")\n";
  if (r.movie.empty())
    std::cout << "ffmpeg is not on PATH: no movie made\n";
  else
    std::cout << "wrote " << r.movie << " (" << r.fps << " frames per second"
              << (a.fps > 0 ? ")\n" : ", real time)\n");
}

void render_any(const RenderArgs& a, const knit::RenderOptions& o);

void check_png_name(const std::string& out) {
  std::string ext = fs::path(out).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext != ".png")
    throw std::runtime_error("--out " + out + ": knitsim writes PNG images; give a .png name");
}

void run_render(const RenderArgs& a) {
  knit::RenderOptions o = options_from(a);
  o.objects = objects_for(a.input, a.scene, a.no_objects);
  const bool sequence = a.compare.empty() && !a.input.empty() && fs::is_directory(a.input);
  if (!sequence) check_png_name(a.out);
  const bool existed = fs::exists(a.out);
  try {
    render_any(a, o);
  } catch (...) {
    // a failed render leaves nothing it made behind
    std::error_code ec;
    if (!existed) fs::remove_all(a.out, ec);
    throw;
  }
}

void render_any(const RenderArgs& a, const knit::RenderOptions& o) {
  if (!a.compare.empty()) {
    if (!a.input.empty()) throw std::runtime_error("give either a state or --compare, not both");
    if (!a.box.empty())
      throw std::runtime_error(
          "--box: a comparison frames each panel on its own state; "
          "render each state with --box instead");
    render_compare(a, o);
    return;
  }
  if (a.input.empty()) throw std::runtime_error("render: give a state, a directory or --compare");
  if (fs::is_directory(a.input)) {
    render_sequence(a, o);
    return;
  }
  const knit::StateFile s = knit::load_state(a.input);
  note_rows(s, a, a.input);
  const auto t0 = std::chrono::steady_clock::now();
  const knit::Image image = knit::render_state(s, o);
  const double t = seconds_since(t0);
  knit::write_png(image, a.out);
  std::cout << "wrote " << a.out << " (" << o.width << "x" << o.height << ", " << s.num_seg()
            << " segments, " << t << " s)\n";
}

}  // namespace

void register_render(CLI::App& app) {
  auto a = std::make_shared<RenderArgs>();
  CLI::App* sub = app.add_subcommand(
      "render", "ray-trace a state (or .yarns/.bcc/.obj), a directory of states, or a comparison");
  add_path(sub, "input", a->input, "state file or directory of .kstate files",
           "none: give a state, a directory or --compare")
      ->check(existing_path());
  add_out_option(sub, a->out, "output PNG (a directory for a sequence)");
  add_text(sub, "--size", a->size, "image size, width x height", "pixels (WxH)", a->size,
           "1 to 16384 each way");
  add_choice(sub, "--view", a->view,
             "front, back, side, iso (relative to the knit's thinnest axis) or scene (+z up, for "
             "knits among objects)",
             {"front", "back", "side", "iso", "scene"});
  sub->add_flag("--color-rows", a->color_rows, "alternate colours by stitch row");
  add_overwrite_flag(
      sub, a->overwrite,
      "for a sequence: replace the frames of an earlier render in the --out directory");
  add_integer(sub, "--spp", a->spp, "samples per pixel", 1, 1024, "count per pixel");
  add_integer(sub, "--shadow-rays", a->shadow_rays, "soft-shadow rays per sample", 0, 256,
              "count per sample");
  add_integer(sub, "--ao-rays", a->ao_rays, "ambient-occlusion rays per sample", 0, 256,
              "count per sample");
  sub->add_option("--compare", a->compare)
      ->expected(2, 64)
      ->check(existing_file())
      ->type_name("PATH")
      ->description("states to place side by side\n" +
                    value_line("paths (2 to 64)", "none (one state or directory)"));
  add_text(sub, "--labels", a->labels, "comma-separated labels for --compare", "text",
           "the states' file names");
  add_path(sub, "--scene", a->scene, "draw this scene's objects under the yarn",
           "the scene a simulation's summary.json beside the input names")
      ->check(existing_file());
  sub->add_flag("--no-objects", a->no_objects, "draw the yarn alone");
  sub->add_flag("--no-scale-bar", a->no_scale_bar, "no scale bar (cm) in the corner");
  sub->add_option("--box", a->box)
      ->expected(6)
      ->delimiter(',')
      ->type_name("FLOAT")
      ->check(number_in(closed(-1e6, 1e6)))
      ->description(
          "X0,Y0,Z0,X1,Y1,Z1: frame this box (world axes) instead of the whole knit and its "
          "objects, for a close-up (yarn outside it may be cut by the image's edge); a "
          "sequence keeps it for every frame\n" +
          value_line("cm", "none (the whole knit and its objects)",
                     range_text(closed(-1e6, 1e6)) + " each"));
  add_number(sub, "--fps", a->fps, "frame rate of the movie made from a sequence",
             "frames per second", closed(1, 240),
             "the simulation's real time, at most " + number_text(knit::MAX_MOVIE_FPS) +
                 " frames per second");
  sub->callback([a] { run_render(*a); });
}

const bool render_added = add_command(40, register_render);

}  // namespace knitsim
