// knitsim params: every parameter of the yarn model as params.def declares it — name,
// group, unit, default, working range and what it is — as text or as JSON (of which the
// docs' parameters page is made).
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

}  // namespace

void register_params(CLI::App& app) {
  struct Opts {
    bool json = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand(
      "params", "list the yarn model's parameters: unit, default, working range, meaning");
  cmd->add_flag("--json", o->json,
                "as JSON: one object per parameter (the docs' parameters page is made of it)");
  cmd->callback([o]() {
    if (o->json) {
      nlohmann::json list = nlohmann::json::array();
      for (const knit::ParamDecl& d : knit::param_table()) {
        nlohmann::json e = {{"name", d.name},
                            {"group", d.group},
                            {"unit", d.unit},
                            {"default", knit::param_json(d, knit::Params{})},
                            {"relaxation", knit::param_json(d, knit::Params::relaxation())},
                            {"doc", d.doc},
                            {"option", d.option()}};
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
                << (d.unit[0] ? std::string(" ") + d.unit : std::string()) << "  " << range_of(d)
                << "  " << d.doc << "\n";
  });
}

const bool params_added = add_command(85, register_params);

}  // namespace knitsim
