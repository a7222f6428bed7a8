#pragma once
// What the three files of ContactTerm (contact_term.cpp: evaluation and records;
// contact_pairs.cpp: the BVH traversal and the pair kernel; contact_reuse.cpp: the
// linearised reuse and the operator stiffness) share. Not part of the library's interface.
#include <Eigen/Core>
#include <chrono>

#include "knit/model/model.hpp"

namespace knit::contact_detail {

using Clock = std::chrono::steady_clock;

inline double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

/// whether contact damping acts: material damping set and a velocity given
inline bool has_damping(const Model& model, const Eigen::VectorXd& q, const Eigen::VectorXd& v) {
  return v.size() == q.size() &&
         (model.params.material.k_dt != 0 || model.params.material.k_dn != 0);
}

}  // namespace knit::contact_detail
