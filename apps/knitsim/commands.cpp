#include "commands.hpp"

#include <algorithm>
#include <utility>
#include <vector>

namespace knitsim {

namespace {

std::vector<std::pair<int, RegisterCommand>>& commands() {
  static std::vector<std::pair<int, RegisterCommand>> added;  // built on first use
  return added;
}

}  // namespace

bool add_command(int order, RegisterCommand register_command) {
  commands().emplace_back(order, register_command);
  return true;
}

void register_commands(CLI::App& app) {
  std::vector<std::pair<int, RegisterCommand>> sorted = commands();
  std::stable_sort(sorted.begin(), sorted.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& [order, register_command] : sorted) register_command(app);
}

}  // namespace knitsim
