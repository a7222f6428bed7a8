#pragma once
// The physical terms a model's step sums, in one registry: each term's name, when the
// model has it, and how it is made. The Simulator's default terms are the registry's
// that apply, in its order (the order their forces are summed in). Adding a term is its
// file pair (energy/, contact/, objects/: value, gradient, Hessian, with a
// finite-difference test) and one entry here.
#include <memory>
#include <vector>

#include "knit/energy/term.hpp"
#include "knit/model/model.hpp"

namespace knit {

struct TermEntry {
  const char* name;                             ///< as Term::name() reports it
  bool (*applies)(const Model& model);          ///< whether the model has the term
  std::unique_ptr<Term> (*make)(const Model&);  ///< the term for the model
};

/// Every term, in the order a step sums their forces.
const std::vector<TermEntry>& term_registry();

/// The terms of `model`: the registry's that apply to it, in its order.
std::vector<std::unique_ptr<Term>> default_terms(const Model& model);

}  // namespace knit
