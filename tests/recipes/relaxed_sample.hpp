#pragma once
// The relaxed samples the stretch tests pull: small stockinettes relaxed for 0.1 s by
// `knitsim relax`, shipped in tests/data/samples/ (see its README.md) so that each test
// process reads one instead of relaxing it again (25 s under the sanitizers).
#include <string>

namespace knit {

/// The path of the shipped `rows` × `cols` relaxed stockinette (6×7 and 5×6 exist).
inline std::string relaxed_stockinette_sample(int rows, int cols) {
  return std::string(KNIT_TEST_DATA) + "/samples/stockinette_" + std::to_string(rows) + "x" +
         std::to_string(cols) + ".kstate";
}

}  // namespace knit
