#include "common.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>

#include <tbb/info.h>

#include "knit/io/export.hpp"
#include "knit/io/states.hpp"
#include "knit/model/params.hpp"
#include "knit/scene/scene_objects.hpp"
#include "knit/solver/interrupt.hpp"

namespace knitsim {

namespace {

std::vector<std::string> g_args;
std::string g_program = "knitsim";

std::string shell_quote(const std::string& s) {
  if (!s.empty() && s.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                        "0123456789-_./=:,+@%") == std::string::npos)
    return s;
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::string join_quoted(const std::string& program, const std::vector<std::string>& args) {
  std::string out = program;
  for (const std::string& a : args) out += " " + shell_quote(a);
  return out;
}

}  // namespace

void set_command_line(int argc, char** argv) {
  g_args.assign(argv + 1, argv + argc);
  g_program = "knitsim";
}

const std::vector<std::string>& command_args() {
  return g_args;
}

std::string command_line() {
  return join_quoted(g_program, g_args);
}

CLI::Validator finite_range(double lo, double hi) {
  const std::string desc = "in [" + knit::short_number(lo) + ", " + knit::short_number(hi) + "]";
  return CLI::Validator(
      [lo, hi, desc](std::string& text) -> std::string {
        char* end = nullptr;
        const double x = std::strtod(text.c_str(), &end);
        if (end == text.c_str() || *end != '\0') return "'" + text + "' is not a number";
        if (!std::isfinite(x))
          return "'" + text + "' is not a finite number (expected one " + desc + ")";
        if (x < lo || x > hi)
          return knit::short_number(x) + " is outside the working range " + desc.substr(3);
        return "";
      },
      "FLOAT " + desc);
}

CLI::Validator param_check(const std::string& name) {
  const knit::ParamRange& r = knit::param_range(name);
  return finite_range(r.min, r.max);
}

CLI::Validator finite_positive(double hi) {
  const std::string desc = hi < 1e300 ? "in (0, " + knit::short_number(hi) + "]" : "> 0";
  return CLI::Validator(
      [hi, desc](std::string& text) -> std::string {
        char* end = nullptr;
        const double x = std::strtod(text.c_str(), &end);
        if (end == text.c_str() || *end != '\0') return "'" + text + "' is not a number";
        if (!std::isfinite(x))
          return "'" + text + "' is not a finite number (expected one " + desc + ")";
        if (!(x > 0) || x > hi) return knit::short_number(x) + " is not " + desc;
        return "";
      },
      "FLOAT " + desc);
}

void add_threads_option(CLI::App* cmd, int& threads) {
  cmd->add_option("--threads,-j", threads, "worker threads (0 = all cores)")
      ->check(CLI::Range(0, 4096));
}

std::unique_ptr<tbb::global_control> make_thread_control(int threads) {
  if (threads <= 0) return nullptr;
  // TBB runs no more workers than the machine has cores: say so rather than run fewer
  // than asked in silence
  const int cores = tbb::info::default_concurrency();
  if (cores > 0 && threads > cores)
    std::cerr << "knitsim: note: --threads " << threads << ": this machine runs " << cores
              << (cores == 1 ? " thread" : " threads") << " at once; using " << cores << "\n";
  return std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                               static_cast<size_t>(threads));
}

void add_integrator_option(CLI::App* cmd, std::string& integrator) {
  cmd->add_option("--integrator", integrator,
                  "explicit: explicit midpoint for every term (the reference); imex: the same "
                  "but the length energy taken by a linearly implicit Euler step, which lifts "
                  "the time-step limit its stiffness sets; imex-contact: yarn–yarn contact "
                  "implicit too (each segment's own contact stiffness in the solve, the "
                  "coupling between segments at the step's start velocity unless the scene "
                  "sets contact_solve_tolerance), which lifts the limit contact sets in "
                  "simulation (a 42×32 knit hanging holds 1.6e-3 s, not 2e-3 s: watch the "
                  "closest approach d; docs/model.md §5.2)")
      ->check(CLI::IsMember(knit::integrator_names()));
}

void add_implicit_bending_option(CLI::App* cmd, bool& implicit_bending) {
  cmd->add_flag("--implicit-bending,!--no-implicit-bending", implicit_bending,
                "with --integrator imex or imex-contact: the bending energy implicit too (its "
                "stiffness in the solve), which lifts the time-step limit bending sets "
                "(docs/model.md §5.2; --no-implicit-bending: explicit, where a resumed "
                "relaxation had it)");
}

void add_end_mass_floor_option(CLI::App* cmd, double& floor) {
  cmd->add_option("--end-mass-floor", floor,
                  "each yarn end's two control points get at least this fraction of an interior "
                  "one's mass (default 0: the row sums, 1/24 at the last point; 0.5 stops a free "
                  "end jittering when nothing damps it, as with --yarn-friction)")
      ->check(param_check("end_mass_floor"));
}

void add_max_step_halvings_option(CLI::App* cmd, int& halvings) {
  cmd->add_option("--max-step-halvings", halvings,
                  "a step that fails (the yarn torn apart in it, a value not finite, the "
                  "projection not converged) is taken again in two halves, up to this many "
                  "times (h/2ⁿ); a simulation keeps the halved step to its end, a FIRE "
                  "relaxation tries h again after 20 good steps; the summary's step_halvings "
                  "counts them (default 0: the run stops at the first failed step)")
      ->check(param_check("max_step_halvings"));
}

void add_contact_solve_tolerance_option(CLI::App* cmd, double& tolerance, const std::string& more) {
  cmd->add_option("--contact-solve-tolerance", tolerance,
                  "with --integrator imex-contact: 0 (the default) solves each step once, "
                  "contact's coupling between segments taken at the step's start velocity; "
                  "> 0 solves the whole linear system by conjugate gradients until the "
                  "residual is this fraction of its right-hand side (docs/model.md §5.2)" +
                      more)
      ->check(param_check("contact_solve_tolerance"));
}

void add_contact_reuse_option(CLI::App* cmd, double& reuse) {
  cmd->add_option("--contact-reuse", reuse,
                  "with --integrator imex-contact: reuse an exact contact evaluation's "
                  "linearisation (and, without length constraints, the step's matrix) while "
                  "every control point stays within this many yarn radii of where it was "
                  "made; 0 (the default) evaluates contact every step. 0.05 cuts a 42×32 "
                  "FIRE relaxation's step by a third to a half (docs/model.md §5.2)")
      ->check(param_check("contact_reuse"));
}

void add_export_option(CLI::App* cmd, std::string& format) {
  cmd->add_option(
         "--export", format,
         "also export the result: usd (every state, time-sampled, as frames.usda), or the "
         "final state as final.EXT in obj, bcc, ply, vtp (polylines), obj-mesh, ply-mesh or "
         "glb (yarn tubes); `knitsim export` has the options")
      ->check(CLI::IsMember(knit::export_formats()));
}

void export_run(const std::string& out_dir, const std::string& format,
                const std::vector<std::shared_ptr<const knit::SceneObject>>& objects) {
  namespace fs = std::filesystem;
  if (format.empty()) return;
  const fs::path dir(out_dir);
  if (format == "usd") {
    std::vector<knit::StateFile> frames;
    std::vector<double> times;
    const fs::path frames_dir = dir / "frames";
    const std::vector<std::string> paths =
        fs::exists(frames_dir) ? knit::list_state_files(frames_dir.string())
                               : std::vector<std::string>{(dir / "final.kstate").string()};
    for (const std::string& p : paths) {
      frames.push_back(knit::read_state_file(p));
      times.push_back(frames.back().state.time);
    }
    knit::export_usd(frames, times, (dir / "frames.usda").string(), objects);
    std::cout << "exported " << frames.size() << " states to " << (dir / "frames.usda").string()
              << "\n";
    return;
  }
  const knit::StateFile final_state = knit::read_state_file((dir / "final.kstate").string());
  const std::string path = (dir / ("final" + knit::export_extension(format))).string();
  knit::ExportOptions options;
  options.objects = objects;
  knit::export_state(final_state, format, path, options);
  std::cout << "exported the final state to " << path << "\n";
}

void print_report(const knit::RunReport& report, const std::string& out_dir) {
  const auto& s = report.summary;
  std::cout << "status " << s["status"].get<std::string>() << ": " << report.steps << " steps, "
            << quantity(s["sim_time_s"], "s") << " simulated in " << quantity(s["wall_time_s"], "s")
            << " wall (" << s["threads"].get<int>() << " threads); outputs in " << out_dir << "/\n";
  if (report.status == knit::StepStatus::INTERRUPTED) {
    std::cerr << "knitsim: " << report.message << "; the state is in " << out_dir
              << "/final.kstate\n";
    if (s.contains("resume_command"))
      std::cerr << "  to go on: " << s["resume_command"].get<std::string>() << "\n";
    return;
  }
  if (!report.message.empty())
    std::cerr << "knitsim: " << report.message << "\n  last good state: " << out_dir
              << "/last_good.kstate\n";
}

std::string resume_command(const std::string& out_dir,
                           const std::vector<std::pair<std::string, std::string>>& replace) {
  std::vector<std::string> args;
  auto replaced = [&](const std::string& a) {
    if (a == "--resume") return true;
    for (const auto& [name, value] : replace)
      if (a == name) return true;
    return false;
  };
  for (size_t k = 0; k < g_args.size(); ++k) {
    const std::string& a = g_args[k];
    if (a == "--overwrite") continue;
    if (replaced(a)) {
      ++k;  // and its value
      continue;
    }
    const size_t eq = a.find('=');
    if (eq != std::string::npos && replaced(a.substr(0, eq))) continue;
    args.push_back(a);
  }
  args.push_back("--resume");
  args.push_back((std::filesystem::path(out_dir) / "final.kstate").string());
  std::string command = join_quoted(g_program, args);
  // a placeholder such as {time_left} is filled in later with a number, which needs no
  // quotes: it stays bare
  for (const auto& [name, value] : replace) {
    const bool placeholder = value.size() > 2 && value.front() == '{' && value.back() == '}';
    command += " " + shell_quote(name) + " " + (placeholder ? value : shell_quote(value));
  }
  return command;
}

void finish_run(const knit::RunReport& report, const std::string& out_dir,
                const std::string& export_format,
                const std::vector<std::shared_ptr<const knit::SceneObject>>& objects) {
  print_report(report, out_dir);
  end_if_interrupted(report);
  export_run(out_dir, export_format, objects);
  if (report.status != knit::StepStatus::OK) throw RunFailed();
}

void end_if_interrupted(const knit::RunReport& report) {
  if (report.status != knit::StepStatus::INTERRUPTED) return;
  const int sig = knit::interrupt_signal();
  throw RunInterrupted{sig != 0 ? sig : 2};
}

void add_provenance(nlohmann::json& extra) {
  extra["command_line"] = command_line();
}

std::string quantity(const nlohmann::json& value, const std::string& unit) {
  if (!value.is_number()) return "not measured";
  if (value.is_number_integer()) return value.dump() + (unit.empty() ? "" : " " + unit);
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", value.get<double>());
  return unit.empty() ? std::string(buf) : std::string(buf) + " " + unit;
}

std::vector<std::shared_ptr<const knit::SceneObject>> objects_for(const std::string& input,
                                                                  const std::string& scene,
                                                                  bool no_objects) {
  namespace fs = std::filesystem;
  if (no_objects) return {};
  if (!scene.empty()) return knit::load_scene_objects(scene);
  if (input.empty()) return {};
  const fs::path in = fs::absolute(input);
  const fs::path dir = fs::is_directory(in) ? in : in.parent_path();
  for (const fs::path& d : {dir, dir.parent_path()}) {
    const fs::path summary = d / "summary.json";
    if (!fs::is_regular_file(summary)) continue;
    try {
      const nlohmann::json s = knit::parse_json_file(summary.string());
      if (!s.contains("scene") || !s["scene"].is_string()) return {};
      const std::string path = s["scene"].get<std::string>();
      if (!fs::is_regular_file(path)) return {};
      auto objects = knit::load_scene_objects(path);
      if (!objects.empty())
        std::cout << "with the objects of " << path << " (named by " << summary.string()
                  << "; --no-objects leaves them out)\n";
      return objects;
    } catch (const std::exception&) {
      return {};  // not a simulation's summary, or its scene no longer parses: the yarn alone
    }
  }
  return {};
}

}  // namespace knitsim
