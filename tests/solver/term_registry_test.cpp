// The term registry (solver/terms.hpp) is what a step sums: each entry makes the term it
// names, and a model gets exactly the entries that apply to it, in the registry's order.
#include <gtest/gtest.h>

#include <string>

#include "knit/model/model.hpp"
#include "knit/solver/simulator.hpp"
#include "knit/solver/terms.hpp"
#include "yarn_setups.hpp"

namespace knit {
namespace {

TEST(TermRegistry, EachEntryMakesTheTermItNamesInOrder) {
  Params p;
  p.material.k_global = 0.5;  // every optional term but the object penalty applies
  ModelBuilder b;
  b.add_yarn(test::line(12, 6.0));
  const Model m = b.build(p);
  const auto terms = default_terms(m);
  std::vector<std::string> expected;
  for (const TermEntry& e : term_registry())
    if (e.applies(m)) expected.push_back(e.name);
  ASSERT_EQ(terms.size(), expected.size());
  for (size_t k = 0; k < terms.size(); ++k) EXPECT_EQ(std::string(terms[k]->name()), expected[k]);
  EXPECT_EQ(expected, (std::vector<std::string>{"gravity", "bending", "length", "global_damping",
                                                "contact"}));
  // what the Simulator sums is the same list
  const Simulator sim(m);
  ASSERT_EQ(sim.terms().size(), terms.size());
  for (size_t k = 0; k < terms.size(); ++k) EXPECT_EQ(sim.terms()[k]->name(), terms[k]->name());
  // without global damping and contact, those two are left out
  p.material.k_global = 0;
  p.material.contact = false;
  const auto fewer = default_terms(b.build(p));
  EXPECT_EQ(fewer.size(), 3u);
}

}  // namespace
}  // namespace knit
