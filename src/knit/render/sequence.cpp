#include "knit/render/sequence.hpp"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "knit/io/process.hpp"

namespace knit {

namespace fs = std::filesystem;

SequenceResult render_sequence(const std::vector<std::string>& files, RenderOptions o,
                               const std::string& out_dir, double fps) {
  SequenceResult r;
  if (files.empty()) return r;
  // one camera for the whole sequence: frame the union of every state's bounds
  if (!o.frame) {
    Eigen::AlignedBox3d box;
    for (const auto& f : files) box.extend(scene_bounds(read_state_file(f), o.objects));
    o.frame = box;
  }
  const auto t0 = std::chrono::steady_clock::now();
  for (size_t i = 0; i < files.size(); ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%04zu.png", i);
    write_png(render_state(read_state_file(files[i]), o), (fs::path(out_dir) / name).string());
  }
  r.frames = static_cast<int>(files.size());
  r.seconds_per_frame =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / r.frames;
  const std::string ffmpeg = find_executable("ffmpeg");
  if (ffmpeg.empty()) return r;
  const std::string movie = (fs::path(out_dir) / "animation.mp4").string();
  const std::string tmp = (fs::path(out_dir) / "animation.tmp.mp4").string();
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
