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
#include "knit/run/interrupt.hpp"
#include "knit/scene/scene_objects.hpp"

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
  if (s.contains("crossings")) {
    const auto& c = s["crossings"];
    std::cout << "crossing check: " << c["steps_checked"] << " steps checked, " << c["count"]
              << (c["count"] == 1 ? " crossing" : " crossings");
    if (!c["first"].is_null())
      std::cout << "; the first at t = " << quantity(c["first"]["time_s"], "s") << ", segments "
                << c["first"]["segments"][0] << " and " << c["first"]["segments"][1] << " (yarns "
                << c["first"]["yarns"][0] << " and " << c["first"]["yarns"][1] << ")";
    std::cout << "\n";
  }
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
