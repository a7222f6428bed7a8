#pragma once
// Procedural yarn geometry for contact tests and benchmarks: not a knit generator (see
// pattern/ for that), only inputs with realistic contact structure.
#include <cstdint>

#include "knit/model/model.hpp"

namespace knit {

/// Rows of interlocking loops: each row is one open yarn following Keenan Crane's
/// plain-knit curve γ(t) = (t + a sin 2t, h cos t, d cos 2t), a = 3/2, h = 4, d = 1, tube
/// radius 4/5, rows offset by h + 1/2 (MODEL.md §6), fitted with `segments_per_loop`
/// segments per loop. The curve is scaled so its tube radius is `squeeze · radius` (cm):
/// squeeze = 1 is the snug fit (touching, d ≈ 1), squeeze < 1 presses the loops into
/// contact (d ≈ squeeze), as in relaxed fabric.
ModelBuilder knit_like_sample(int rows, int loops_per_row, int segments_per_loop, double radius,
                              double squeeze = 0.9);

/// `yarns` smooth random walks of `segments` segments each (control points `step` cm
/// apart, direction turning by at most `turn` rad per step) confined to a cube of side
/// `box` cm centred at the origin. Overlaps are likely: a stress input for culling.
ModelBuilder random_tangle(int yarns, int segments, double box, std::uint32_t seed,
                           double step = 0.3, double turn = 0.6);

}  // namespace knit
