#pragma once
// Rendering a sequence of states into numbered frames and a movie: one camera framed on
// the union of every state's bounds (objects included), frames frame_0000.png, … and,
// when ffmpeg is on PATH, animation.mp4 (H.264, yuv420p) beside them. Used by
// `knitsim render DIR` and by recipes that show a run (the stretch test).
#include <string>
#include <vector>

#include "knit/present/render.hpp"

namespace knit {

struct SequenceResult {
  int frames = 0;  ///< frames rendered
  int stride = 1;  ///< every stride-th state was rendered (and the last)
  double fps = 0;  ///< the movie's frame rate
  double seconds_per_frame = 0;
  std::string movie;  ///< path of animation.mp4; empty when ffmpeg is not on PATH
};

/// The most frames per second a real-time movie plays (more states are thinned).
inline constexpr double MAX_MOVIE_FPS = 60;

/// Renders `files` (.kstate, in order of time) into `out_dir` (which must exist and hold
/// no other sequence's frames) and makes a movie of them at `fps` frames per second; with
/// fps <= 0, at the simulation's real time: (states − 1) / (last time − first time), the
/// states thinned to every stride-th so that it stays at most MAX_MOVIE_FPS. Each frame
/// carries its time ("t = 0.250 s") unless `options.caption` is set, and a scale bar
/// when options.scale_bar. `options.frame`, when unset, is the union of the states' scene
/// bounds. Throws std::runtime_error when a frame cannot be written or ffmpeg fails (the
/// movie is written to a temporary name and renamed).
SequenceResult render_sequence(const std::vector<std::string>& files, RenderOptions options,
                               const std::string& out_dir, double fps = 0);

}  // namespace knit
