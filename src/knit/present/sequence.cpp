#include "knit/present/sequence.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "knit/util/process.hpp"
#include "knit/util/run_dir.hpp"

namespace knit {

namespace fs = std::filesystem;

SequenceResult render_sequence(const std::vector<std::string>& files, RenderOptions o,
                               const std::string& out_dir, double fps) {
  SequenceResult r;
  if (files.empty()) return r;
  std::vector<StateFile> states;
  for (const auto& f : files) states.push_back(read_state_file(f));
  // one camera for the whole sequence: frame the union of every state's bounds
  if (!o.frame) {
    Eigen::AlignedBox3d box;
    for (const auto& s : states) box.extend(scene_bounds(s, o.objects));
    o.frame = box;
  }
  // real time: as many frames per second as states per simulated second, thinned to at
  // most MAX_MOVIE_FPS
  const double span = states.back().state.time - states.front().state.time;
  if (fps <= 0) {
    fps = states.size() > 1 && span > 0 ? static_cast<double>(states.size() - 1) / span : 30;
    if (fps > MAX_MOVIE_FPS) {
      r.stride = static_cast<int>(std::ceil(fps / MAX_MOVIE_FPS));
      fps /= r.stride;
    }
  }
  r.fps = fps;
  std::vector<size_t> chosen;
  for (size_t i = 0; i < states.size(); i += static_cast<size_t>(r.stride)) chosen.push_back(i);
  if (chosen.back() + 1 != states.size()) chosen.push_back(states.size() - 1);
  const bool stamp = o.caption.empty();
  const auto t0 = std::chrono::steady_clock::now();
  for (size_t i = 0; i < chosen.size(); ++i) {
    const StateFile& s = states[chosen[i]];
    if (stamp) {
      char caption[64];
      std::snprintf(caption, sizeof caption, "t = %.3f s", s.state.time);
      o.caption = caption;
    }
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%04zu.png", i);
    write_png(render_state(s, o), (fs::path(out_dir) / name).string());
  }
  r.frames = static_cast<int>(chosen.size());
  r.seconds_per_frame =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / r.frames;
  const std::string ffmpeg = find_executable("ffmpeg");
  if (ffmpeg.empty()) return r;
  const std::string movie = (fs::path(out_dir) / "animation.mp4").string();
  const std::string tmp = (fs::path(out_dir) / "animation.tmp.mp4").string();
  claim_run_output(movie);
  claim_run_output(tmp);
  std::string messages;
  const int rc = run_process({ffmpeg, "-y", "-loglevel", "error", "-framerate", std::to_string(fps),
                              "-i", (fs::path(out_dir) / "frame_%04d.png").string(), "-vf",
                              "scale=trunc(iw/2)*2:trunc(ih/2)*2", "-pix_fmt", "yuv420p", tmp},
                             messages);
  if (rc != 0) {
    fs::remove(tmp);
    throw std::runtime_error(movie + ": ffmpeg failed: " + messages);
  }
  fs::rename(tmp, movie);
  r.movie = movie;
  return r;
}

}  // namespace knit
