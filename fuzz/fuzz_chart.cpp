// libFuzzer target: the text pattern readers — the knit chart reader (parse_chart) with the
// tiling of what it read, and the knitout program reader (parse_knitout) — fed the same
// input (the seeds hold charts and knitout programs).
// std::invalid_argument is a clean rejection; crashes, sanitizer reports, hangs and a
// parsed chart that breaks the reader's promises are bugs. (The knit generator that
// follows in `knitsim relax CHART` is left out: under ASan it ran 60 inputs a second, and
// the charts it can be given small enough to stay fast are few enough for its own tests.)
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string_view>

#include "knit/pattern/knitout.hpp"
#include "knit/pattern/pattern.hpp"

namespace {

// what a reader promises of a pattern: at least one row, all rows equally long, only 'k'
// and 'p'
void check_pattern(const knit::Pattern& p) {
  if (p.num_rows() < 1 || p.num_cols() < 1) __builtin_trap();
  for (const auto& row : p.rows) {
    if (static_cast<int>(row.size()) != p.num_cols()) __builtin_trap();
    for (char c : row)
      if (c != 'k' && c != 'p') __builtin_trap();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const knit::KnitoutPiece piece = knit::parse_knitout(text, "fuzz.k");
    check_pattern(piece.pattern);
    // a tube goes around both beds: at least one needle on each
    if (piece.in_the_round && piece.cols() < 2) __builtin_trap();
  } catch (const std::invalid_argument&) {
  }
  try {
    const knit::Pattern p = knit::parse_chart(text, "fuzz.chart");
    check_pattern(p);
    const knit::Pattern t = knit::tile(p, p.num_rows() + 1, p.num_cols() + 2);
    for (int r = 0; r < t.num_rows(); ++r)
      for (int c = 0; c < t.num_cols(); ++c)
        if (t.is_knit(r, c) != p.is_knit(r % p.num_rows(), c % p.num_cols())) __builtin_trap();
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
