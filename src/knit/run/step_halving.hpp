#pragma once
// Steps that are taken again in halves when they fail.
//
// A step of h fails when the yarn tears apart in it (a control point moving more than a
// yarn diameter relative to its neighbour), a value turns non-finite or the projection
// does not converge; the state is then as it was before it (Simulator::step). With
// SolverSettings::max_step_halvings = n > 0 the step is taken again from there as two
// steps of h/2, and so on down to h/2ⁿ; the run fails only where h/2ⁿ fails too. A
// halved step is kept for the next CALM_STEPS steps of h that pass without a failure,
// then the step doubles again, one halving at a time. The run's steps of h, its frames
// and its time stay on the grid of h: each is made of 2ᵏ substeps.
//
// What it is for: a local, passing stiffness (yarns squeezed close under a clamp, a
// relaxation's first steps from a generated yarn) that bounds the step for a while and
// would otherwise end the run or force a small step on all of it. An explicit step near
// its stability limit grows an oscillation for a few steps before it fails; in a
// simulation that is energy the filters and damping then remove, in a relaxation (FIRE)
// it is an uphill step FIRE stops. The summary says how often it happened.
#include <algorithm>
#include <string>

#include "knit/model/run_totals.hpp"
#include "knit/solver/simulator.hpp"

namespace knit {

class HalvingStepper {
 public:
  /// `max_halvings`: n; `calm_steps`: steps of h that pass at a halved step before the
  /// step doubles again (0: never; the run goes on at the step it needed). `from`: where a
  /// resumed run's stepper stood (RunTotals::halving), so that it goes on at that step.
  HalvingStepper(int max_halvings, int calm_steps, const HalvingCounts& from = {})
      : m_max(max_halvings), m_calm_steps(calm_steps), m_counts(from) {
    m_counts.level = std::min(m_counts.level, max_halvings);  // (a resume with fewer allowed)
  }

  /// Advances `state` by h (as Simulator::step, in 2ᵏ substeps): on failure the state is
  /// the last good substep's and the message says how far the step was halved.
  StepResult step(Simulator& sim, State& state, double h);

  /// Its counts and where it stands (those of the run it was resumed from included).
  const HalvingCounts& counts() const { return m_counts; }
  /// Substeps thrown away and taken again in halves.
  long long retried() const { return m_counts.retried; }
  /// The most halvings any step needed.
  int deepest() const { return m_counts.deepest; }
  /// Substeps taken, over all steps (equal to the steps when none was halved).
  long long substeps() const { return m_counts.substeps; }
  /// The halvings the next step starts with.
  int level() const { return m_counts.level; }

 private:
  int m_max;
  int m_calm_steps;
  HalvingCounts m_counts;
};

}  // namespace knit
