// knitsim params: every parameter of the yarn model as params.def declares it — name,
// group, unit, default, working range and what it is — as a table, as Markdown (the page
// docs/parameters.md is this output) or as JSON.
#include <cctype>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "commands.hpp"
#include "knit/model/params.hpp"

namespace knitsim {

namespace {

std::string range_of(const knit::ParamDecl& d) {
  if (d.type == knit::ParamType::BOOLEAN) return "true or false";
  if (d.type == knit::ParamType::CHOICE) {
    std::string names;
    for (const std::string& c : d.choices()) names += (names.empty() ? "" : ", ") + c;
    return names;
  }
  return "[" + knit::short_number(d.min) + ", " + knit::short_number(d.max) + "]";
}

void print_markdown() {
  std::cout << "# Parameters\n\n"
               "Every parameter of the yarn model (MODEL.md §8, Table 1; CGS units), made by "
               "`knitsim params --markdown` from their one declaration, "
               "`src/knit/model/params.def`. A scene sets them under `\"params\"` by name "
               "(docs/scene-format.md); the commands that take one have the option named "
               "alike (`k_len` is `--k-len`), Python the keyword; every front end refuses a "
               "value outside its working range before anything runs. The defaults are the "
               "simulation column; `\"preset\": \"relaxation\"` starts from the relaxation "
               "column (k_len 10000, k_bend 0.005, k_global 1.5, alpha_small and "
               "alpha_large 0.3, no length constraints).\n";
  const char* group = "";
  for (const knit::ParamDecl& d : knit::param_table()) {
    if (std::string(group) != d.group) {
      group = d.group;
      std::cout << "\n## " << static_cast<char>(std::toupper(group[0])) << (group + 1) << "\n\n"
                << "| name | unit | default | working range | what it is |\n"
                << "|---|---|---|---|---|\n";
    }
    std::cout << "| `" << d.name << "` | " << d.unit << " | " << d.default_text() << " | "
              << range_of(d) << " | " << d.doc << " |\n";
  }
}

}  // namespace

void register_params(CLI::App& app) {
  struct Opts {
    bool markdown = false, json = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand(
      "params", "list the yarn model's parameters: unit, default, working range, meaning");
  cmd->add_flag("--markdown", o->markdown, "as a Markdown page (docs/parameters.md)");
  cmd->add_flag("--json", o->json, "as JSON: one object per parameter")->excludes("--markdown");
  cmd->callback([o]() {
    if (o->markdown) return print_markdown();
    if (o->json) {
      nlohmann::json list = nlohmann::json::array();
      for (const knit::ParamDecl& d : knit::param_table()) {
        nlohmann::json e = {{"name", d.name},   {"group", d.group},
                            {"unit", d.unit},   {"default", knit::param_json(d, knit::Params{})},
                            {"doc", d.doc},     {"option", d.option()}};
        if (d.type == knit::ParamType::REAL || d.type == knit::ParamType::INTEGER)
          e["range"] = {d.min, d.max};
        if (d.type == knit::ParamType::CHOICE) e["choices"] = d.choices();
        list.push_back(e);
      }
      std::cout << list.dump(2) << "\n";
      return;
    }
    for (const knit::ParamDecl& d : knit::param_table())
      std::cout << d.group << "." << d.name << " = " << d.default_text()
                << (d.unit[0] ? std::string(" ") + d.unit : std::string()) << "  "
                << range_of(d) << "  " << d.doc << "\n";
  });
}

const bool params_added = add_command(85, register_params);

}  // namespace knitsim
