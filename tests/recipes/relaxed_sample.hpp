#pragma once
// A small stockinette relaxed for 0.1 s and written as `knitsim relax` writes it, once per
// test program and name: the sample the stretch tests pull.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "knit/io/state_file.hpp"
#include "knit/recipes/relax_knit.hpp"

namespace knit {

inline std::string write_relaxed_stockinette(int rows, int cols, const std::string& name) {
  RelaxKnitOptions o;
  o.knit.rows = rows;
  o.knit.cols = cols;
  o.run.max_time = 0.1;
  o.run.progress = false;
  const RelaxResult r = relax_knit("stockinette", o);
  const std::string p = (std::filesystem::path(::testing::TempDir()) / name).string();
  write_state_file(p, make_state_file(r.model, r.state));
  return p;
}

}  // namespace knit
