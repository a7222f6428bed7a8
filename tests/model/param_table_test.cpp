// The parameter table (model/params.def) is the one declaration every reader and writer of
// parameters is made from: these tests set each parameter through one front end and read
// it back through the others.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "app/run_knitsim.hpp"
#include "knit/model/params.hpp"
#include "knit/run/runner.hpp"
#include "knit/scene/json_reader.hpp"
#include "knit/scene/scene.hpp"

namespace knit {
namespace {

// a value of `d` other than its default and inside its range
nlohmann::json other_value(const ParamDecl& d) {
  const Params defaults;
  switch (d.type) {
    case ParamType::BOOLEAN:
      return !(d.get(defaults) != 0);
    case ParamType::CHOICE:
      return d.choices().back() != d.text(defaults) ? d.choices().back() : d.choices().front();
    case ParamType::INTEGER: {
      long long v = static_cast<long long>(d.get(defaults)) + 2;  // +2 keeps an odd count odd
      if (v > d.max) v = static_cast<long long>(d.min);
      return v;
    }
    case ParamType::REAL:
      break;
  }
  const double v = d.get(defaults);
  return v < d.max ? v + 0.5 * (d.max - v) : d.min;  // inside (v, max], or the other end
}

TEST(ParamTable, EveryFieldIsDeclaredOnceWithItsGroup) {
  std::set<std::string> names;
  for (const ParamDecl& d : param_table()) {
    EXPECT_TRUE(names.insert(d.name).second) << d.name << " declared twice";
    const std::string group = d.group;
    EXPECT_TRUE(group == "material" || group == "discretisation" || group == "solver") << group;
    EXPECT_FALSE(std::string(d.doc).empty()) << d.name;
    if (d.type == ParamType::REAL || d.type == ParamType::INTEGER) {
      EXPECT_LE(d.min, d.get(Params{})) << d.name << ": the default is below its range";
      EXPECT_GE(d.max, d.get(Params{})) << d.name << ": the default is above its range";
    }
  }
  // the summary's params hold exactly the table's, each under its group
  const nlohmann::json j = params_json(Params{});
  size_t count = 0;
  for (const char* group : {"material", "discretisation", "solver"}) count += j[group].size();
  EXPECT_EQ(count, param_table().size());
}

// each parameter, set in a scene's "params", is read into its field and written back by
// the summary under the same name: the reader and the writer agree with the table
TEST(ParamTable, EachParameterGoesFromASceneToItsFieldAndTheSummary) {
  for (const ParamDecl& d : param_table()) {
    if (std::string(d.name) == "contact_reuse") continue;  // needs imex-contact: below
    nlohmann::json params = {{d.name, other_value(d)}};
    const Params p = parse_params(JsonReader(params, "test.json", "params"), Params{});
    EXPECT_EQ(param_json(d, p), other_value(d)) << d.name;
    EXPECT_NE(param_json(d, p), param_json(d, Params{})) << d.name << ": the value did not change";
    EXPECT_EQ(params_json(p)[d.group][d.name], other_value(d)) << d.name;
    // and nothing else changed
    for (const ParamDecl& e : param_table()) {
      if (&e != &d) {
        EXPECT_EQ(param_json(e, p), param_json(e, Params{})) << d.name << " set " << e.name;
      }
    }
  }
  nlohmann::json both = {{"integrator", "imex-contact"}, {"contact_reuse", 0.5}};
  EXPECT_EQ(parse_params(JsonReader(both, "test.json", "params"), Params{}).solver.contact_reuse,
            0.5);
}

// outside its range, every number is refused naming the key and the range
TEST(ParamTable, AValueOutsideItsRangeIsRefusedNamingTheKey) {
  for (const ParamDecl& d : param_table()) {
    if (d.type != ParamType::REAL && d.type != ParamType::INTEGER) continue;
    const double beyond = d.max + (d.type == ParamType::INTEGER ? 2 : d.max + 1);
    nlohmann::json params = {{d.name, beyond}};
    try {
      parse_params(JsonReader(params, "test.json", "params"), Params{});
      ADD_FAILURE() << d.name << " = " << beyond << " was accepted";
    } catch (const std::exception& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(d.name), std::string::npos) << msg;
      EXPECT_NE(msg.find("test.json"), std::string::npos) << msg;
    }
    Params p;
    d.set(p, beyond);
    EXPECT_THROW(validate_params(p), std::invalid_argument) << d.name;
  }
}

// `knitsim params --json`, of which the docs' parameters page is made, is the table
TEST(ParamTable, TheProgramListsTheTable) {
  const cli_test::Result r = cli_test::run("params --json");
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json list = nlohmann::json::parse(r.output);
  ASSERT_EQ(list.size(), param_table().size());
  for (size_t k = 0; k < list.size(); ++k) {
    const ParamDecl& d = param_table()[k];
    EXPECT_EQ(list[k]["name"], d.name);
    EXPECT_EQ(list[k]["default"], param_json(d, Params{})) << d.name;
    EXPECT_EQ(list[k]["relaxation"], param_json(d, Params::relaxation())) << d.name;
    EXPECT_EQ(list[k]["option"], d.option()) << d.name;
    if (d.type == ParamType::REAL || d.type == ParamType::INTEGER) {
      EXPECT_EQ(list[k]["range"], nlohmann::json({d.min, d.max})) << d.name;
    }
  }
}

}  // namespace
}  // namespace knit
