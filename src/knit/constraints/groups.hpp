#pragma once
// The constraint groups of a model: the rows the projection enforces, built from the
// model's parameters, pins, glues and clamps (the Model holds those as data; the groups
// are the physics). The Simulator builds them for the model it is given.
#include "knit/model/model.hpp"

namespace knit {

/// Builds model.constraint_groups from its parameters, pins, glues and clamps. Rows that a
/// clamp's held control points make redundant are left out: the length row of a segment
/// whose four control points are all held, and a glue whose two points lie on such
/// segments (both are fixed by the clamps already, and redundant rows make the split of
/// forces between groups arbitrary).
void build_constraint_groups(Model& model);

/// `model` with its constraint groups built (build_constraint_groups).
Model with_constraint_groups(Model model);

}  // namespace knit
