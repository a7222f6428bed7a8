#include "common.hpp"

#include <filesystem>
#include <iostream>

#include "knit/io/export.hpp"
#include "knit/io/states.hpp"

namespace knitsim {

void add_threads_option(CLI::App* cmd, int& threads) {
  cmd->add_option("--threads,-j", threads, "worker threads (0 = all cores)")
      ->check(CLI::NonNegativeNumber);
}

std::unique_ptr<tbb::global_control> make_thread_control(int threads) {
  if (threads <= 0) return nullptr;
  return std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                               static_cast<size_t>(threads));
}

void add_export_option(CLI::App* cmd, std::string& format) {
  cmd->add_option(
         "--export", format,
         "also export the result: usd (every state, time-sampled), obj, bcc or ply (final state)")
      ->check(CLI::IsMember({"usd", "obj", "bcc", "ply"}));
}

void export_run(const std::string& out_dir, const std::string& format) {
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
    knit::export_usd(frames, times, (dir / "frames.usda").string());
    std::cout << "exported " << frames.size() << " states to " << (dir / "frames.usda").string()
              << "\n";
    return;
  }
  const knit::StateFile final_state = knit::read_state_file((dir / "final.kstate").string());
  const std::string path = (dir / ("final." + format)).string();
  if (format == "obj") knit::export_obj(final_state, path);
  if (format == "bcc") knit::export_bcc(final_state, path);
  if (format == "ply") knit::export_ply(final_state, path);
  std::cout << "exported the final state to " << path << "\n";
}

void print_report(const knit::RunReport& report, const std::string& out_dir) {
  const auto& s = report.summary;
  std::cout << "status " << s["status"].get<std::string>() << ": " << report.steps << " steps, "
            << s["sim_time_s"].get<double>() << " s simulated in " << s["wall_time_s"].get<double>()
            << " s wall (" << s["threads"].get<int>() << " threads); outputs in " << out_dir
            << "/\n";
  if (!report.message.empty())
    std::cerr << "knitsim: " << report.message << "\n  last good state: " << out_dir
              << "/last_good.kstate\n";
}

}  // namespace knitsim
