// libFuzzer target: the OBJ polyline reader and the spline fit.
#include "fuzz_import.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return knit::fuzz::run(data, size, knit::parse_obj, "fuzz.obj");
}
