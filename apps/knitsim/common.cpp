#include "common.hpp"

#include <iostream>

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
