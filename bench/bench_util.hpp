#pragma once
// Shared helpers for knitsim's benchmarks: machine facts and timing. Every benchmark
// prints one JSON document on stdout.
#include <tbb/global_control.h>
#include <tbb/task_arena.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

namespace knit::bench {

inline nlohmann::json machine_info() {
  std::string model = "unknown";
  std::ifstream cpu("/proc/cpuinfo");
  for (std::string line; std::getline(cpu, line);)
    if (line.rfind("model name", 0) == 0) {
      model = line.substr(line.find(':') + 2);
      break;
    }
  char host[256] = {0};
  gethostname(host, sizeof host - 1);
  return {{"cpu_model", model},
          {"hardware_threads", std::thread::hardware_concurrency()},
          {"host", host},
#ifdef NDEBUG
          {"build", "release"}
#else
          {"build", "debug"}
#endif
  };
}

inline double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace knit::bench
