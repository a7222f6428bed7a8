#include "knit/constraints/groups.hpp"

#include <memory>
#include <string>
#include <vector>

#include "knit/constraints/clamp.hpp"
#include "knit/constraints/glue.hpp"
#include "knit/constraints/inextensibility.hpp"
#include "knit/constraints/pin.hpp"

namespace knit {

void build_constraint_groups(Model& m) {
  m.constraint_groups.clear();
  // segments whose four control points are all held by clamps: their shape is fixed
  std::vector<char> held(m.num_cp(), 0);
  for (const Clamp& c : m.clamps)
    for (int k : c.control_points) held[k] = 1;
  auto fixed = [&](int seg) {
    for (int a = 0; a < 4; ++a)
      if (!held[m.seg_cp[seg] + a]) return false;
    return true;
  };
  if (m.params.solver.length_constraints) {
    std::vector<int> free_segments;
    for (int i = 0; i < m.num_seg(); ++i)
      if (!fixed(i)) free_segments.push_back(i);
    m.constraint_groups.push_back(std::make_shared<LengthGroup>(m, std::move(free_segments)));
  }
  for (size_t k = 0; k < m.pins.size(); ++k)
    m.constraint_groups.push_back(std::make_shared<PinGroup>("pin" + std::to_string(k), m.pins[k]));
  for (size_t k = 0; k < m.glues.size(); ++k)
    if (!fixed(m.glues[k].a.segment) || !fixed(m.glues[k].b.segment))
      m.constraint_groups.push_back(
          std::make_shared<GlueGroup>("glue" + std::to_string(k), m.glues[k]));
  for (const Clamp& c : m.clamps) m.constraint_groups.push_back(std::make_shared<ClampGroup>(c));
}

Model with_constraint_groups(Model model) {
  build_constraint_groups(model);
  return model;
}

}  // namespace knit
