#pragma once
// Rendering a sequence of states into numbered frames and a movie: one camera framed on
// the union of every state's bounds (objects included), frames frame_0000.png, … and,
// when ffmpeg is on PATH, animation.mp4 (H.264, yuv420p) beside them. Used by
// `knitsim render DIR` and by recipes that show a run (the stretch test).
#include <string>
#include <vector>

#include "knit/render/render.hpp"

namespace knit {

struct SequenceResult {
  int frames = 0;
  double seconds_per_frame = 0;
  std::string movie;  ///< path of animation.mp4; empty when ffmpeg is not on PATH
};

/// Renders `files` (.kstate, in order) into `out_dir` (which must exist and hold no other
/// sequence's frames) at `fps` frames per second of movie. `options.frame`, when unset, is
/// the union of the states' scene bounds. Throws std::runtime_error when a frame cannot be
/// written or ffmpeg fails (the movie is written to a temporary name and renamed).
SequenceResult render_sequence(const std::vector<std::string>& files, RenderOptions options,
                               const std::string& out_dir, double fps = 30);

}  // namespace knit
