#include "knit/solver/terms.hpp"

#include <algorithm>

#include "knit/contact/contact_term.hpp"
#include "knit/energy/bending.hpp"
#include "knit/energy/global_damping.hpp"
#include "knit/energy/gravity.hpp"
#include "knit/energy/length.hpp"
#include "knit/objects/object_penalty.hpp"

namespace knit {

const std::vector<TermEntry>& term_registry() {
  static const std::vector<TermEntry> terms = {
      {"gravity", [](const Model&) { return true; },
       [](const Model&) -> std::unique_ptr<Term> { return std::make_unique<Gravity>(); }},
      {"bending", [](const Model&) { return true; },
       [](const Model& m) -> std::unique_ptr<Term> {
         return std::make_unique<BendingEnergy>(m.params.solver.implicit_bending);
       }},
      {"length", [](const Model&) { return true; },
       [](const Model&) -> std::unique_ptr<Term> { return std::make_unique<LengthEnergy>(); }},
      {"global_damping", [](const Model& m) { return m.params.material.k_global > 0; },
       [](const Model&) -> std::unique_ptr<Term> { return std::make_unique<GlobalDamping>(); }},
      {"contact", [](const Model& m) { return m.params.material.contact; },
       [](const Model& m) -> std::unique_ptr<Term> { return std::make_unique<ContactTerm>(m); }},
      {"objects",
       [](const Model& m) {
         return std::any_of(m.objects.begin(), m.objects.end(),
                            [](const auto& o) { return o->penalty; });
       },
       [](const Model& m) -> std::unique_ptr<Term> { return std::make_unique<ObjectPenalty>(m); }},
  };
  return terms;
}

std::vector<std::unique_ptr<Term>> default_terms(const Model& model) {
  std::vector<std::unique_ptr<Term>> terms;
  for (const TermEntry& entry : term_registry())
    if (entry.applies(model)) terms.push_back(entry.make(model));
  return terms;
}

}  // namespace knit
