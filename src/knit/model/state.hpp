#pragma once
// The mutable State: control-point positions and velocities and the time.
#include <Eigen/Core>

namespace knit {

struct State {
  Eigen::VectorXd q;  ///< control points, stacked xyz (cm), length 3·num_cp
  Eigen::VectorXd v;  ///< control-point velocities (cm/s)
  double time = 0;    ///< s
  bool finite() const { return q.allFinite() && v.allFinite(); }
};

}  // namespace knit
