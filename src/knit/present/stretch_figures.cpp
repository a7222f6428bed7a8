#include "knit/present/stretch_figures.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "knit/io/states.hpp"
#include "knit/present/plot.hpp"
#include "knit/present/render.hpp"
#include "knit/present/sequence.hpp"
#include "knit/util/run_dir.hpp"

namespace knit {

namespace fs = std::filesystem;

namespace {

// the strains the renders show: 0, 0.25, 0.5, 1 up to `to`, and `to` itself
std::vector<double> render_strains(double to) {
  std::vector<double> e;
  for (double x : {0.0, 0.25, 0.5, 1.0})
    if (x < to * (1 - 1e-9)) e.push_back(x);
  e.push_back(to);
  return e;
}

std::string strain_label(double e) {
  std::ostringstream s;
  s << std::setprecision(3) << e;
  return s.str();
}

// renders of the frames nearest each shown strain (first pull only), side by side, and a
// movie of every frame; returns the summary's "renders" entry. A pull that stopped before
// `to` shows the strains it passed and the last one it reached.
nlohmann::json render_stretch(const std::string& out_dir, const std::vector<StretchSample>& curve,
                              double to, const StretchOptions& o) {
  const fs::path dir(out_dir);
  const std::vector<std::string> frames = list_state_files(out_dir);
  if (frames.size() != curve.size())
    throw std::runtime_error(out_dir + ": " + std::to_string(frames.size()) + " frames for " +
                             std::to_string(curve.size()) + " samples of the curve");
  RenderOptions ro;
  ro.width = o.render_width;
  ro.height = o.render_height;
  ro.view = View::FRONT;
  ro.color_rows = true;
  ro.scale_bar = true;
  // one scale for every picture: the box of every frame
  Eigen::AlignedBox3d box;
  for (const std::string& f : frames) box.extend(state_bounds(read_state_file(f)));
  ro.frame = box;
  size_t end = curve.size();  // the first pull: up to the first sample at `to`
  for (size_t i = 0; i < curve.size(); ++i)
    if (curve[i].strain >= to * (1 - 1e-9)) {
      end = i + 1;
      break;
    }
  double reached = 0;
  for (size_t i = 0; i < end; ++i) reached = std::max(reached, curve[i].strain);
  const bool stopped = reached < to * (1 - 1e-9);
  if (stopped) to = reached;
  fs::create_directories(dir / "renders");
  claim_run_output((dir / "renders").string());
  std::vector<Image> panels;
  std::vector<std::string> labels;
  nlohmann::json shown = nlohmann::json::object();
  // a held curve shows the ends of its holds (the unrelaxed start only if it has none)
  const bool held =
      std::any_of(curve.begin(), curve.end(), [](const StretchSample& s) { return s.equilibrium; });
  for (double e : render_strains(to)) {
    size_t best = curve.size();
    for (size_t i = 0; i < end; ++i)
      if ((!held || curve[i].equilibrium) &&
          (best == curve.size() ||
           std::abs(curve[i].strain - e) < std::abs(curve[best].strain - e)))
        best = i;
    if (best == curve.size()) best = 0;
    panels.push_back(render_state(read_state_file(frames[best]), ro));
    const std::string name = "renders/strain_" + strain_label(e) + ".png";
    write_png(panels.back(), (dir / name).string());
    labels.push_back("strain " + strain_label(curve[best].strain));
    shown[strain_label(e)] = name;
  }
  write_png(compose_side_by_side(panels, labels), (dir / "stretch_renders.png").string());
  fs::create_directories(dir / "movie");
  claim_run_output((dir / "movie").string());
  // movie frames at a lighter sampling than the stills
  ro.spp = ro.shadow_rays = ro.ao_rays = 2;
  // at the pull's real time, each frame with its time
  const SequenceResult movie = render_sequence(frames, ro, (dir / "movie").string());
  nlohmann::json renders = {{"images", shown},
                            {"side_by_side", "stretch_renders.png"},
                            {"movie", movie.movie.empty() ? nlohmann::json(nullptr)
                                                          : nlohmann::json("movie/animation.mp4")}};
  if (stopped) renders["stopped_at_strain"] = reached;
  return renders;
}

}  // namespace

nlohmann::json write_stretch_figures(const StretchOptions& o,
                                     const std::vector<StretchSample>& curve,
                                     const std::string& label, bool ended) {
  const fs::path dir(o.out_dir);
  if (!find_gnuplot().empty()) {
    PlotSeries fixed{"fixed clamp", {}, {}}, pulled{"moving clamp", {}, {}}, width{"width", {}, {}};
    // a held curve is the ends of its holds
    const bool held = std::any_of(curve.begin(), curve.end(),
                                  [](const StretchSample& s) { return s.equilibrium; });
    for (const StretchSample& s : curve) {
      if (held && !s.equilibrium) continue;
      fixed.x.push_back(s.strain);
      fixed.y.push_back(s.force_fixed);
      pulled.x.push_back(s.strain);
      pulled.y.push_back(s.force_moving);
      width.x.push_back(s.strain);
      width.y.push_back(s.width);
    }
    plot_series({pulled, fixed}, "nominal strain", "force along the pull (dyn)",
                "Stretch: " + label, (dir / "stretch_force.png").string());
    plot_series({width}, "nominal strain", "width across the pull at the middle (cm)",
                "Width: " + label, (dir / "stretch_width.png").string());
  }
  if (!(o.render && o.write_frames && ended)) return nullptr;
  return render_stretch(o.out_dir, curve, o.to_strain, o);
}

std::string plot_stretch_runs(const std::vector<std::string>& dirs, const std::string& out_png) {
  std::vector<PlotSeries> series;
  for (const std::string& d : dirs) {
    const std::string csv = (fs::path(d) / "stretch.csv").string();
    const CsvTable t = read_csv(csv);
    const int x = t.column("strain", csv), y = t.column("force_moving_dyn", csv);
    std::string label = fs::path(d).filename().string();
    std::ifstream in(fs::path(d) / "summary.json");
    const nlohmann::json s = nlohmann::json::parse(in, nullptr, false);
    if (s.is_object() && s.contains("direction") && s["direction"].is_string()) {
      label =
          (s.contains("pattern") && s["pattern"].is_string() ? s["pattern"].get<std::string>() + " "
                                                             : std::string()) +
          s["direction"].get<std::string>();
      if (s.contains("bind_off") && s["bind_off"] == true) label += ", bound off";
      if (s.contains("cast_on") && s["cast_on"] == true) label += ", cast on";
      if (s.contains("model") && s["model"] == "sheet") {
        label += ", sheet";
      } else if (s.contains("protocol") && s["protocol"] == "hold") {
        label += ", held";
      } else if (s.contains("speed_cm_s") && s["speed_cm_s"].is_number()) {
        std::ostringstream speed;
        speed << std::setprecision(3) << s["speed_cm_s"].get<double>();
        label += ", " + speed.str() + " cm/s";
      }
      // yarn friction changes the model: say so (the paper's model has none)
      const nlohmann::json::json_pointer at("/params/material/yarn_friction");
      const nlohmann::json mu = s.contains(at) ? s.at(at) : nlohmann::json();
      if (mu.is_number() && mu.get<double>() > 0) {
        std::ostringstream text;
        text << std::setprecision(3) << mu.get<double>();
        label += ", friction " + text.str();
      }
    }
    // a held run's curve is the ends of its holds (older runs have no such column)
    const auto eq = std::find(t.columns.begin(), t.columns.end(), "equilibrium");
    const int e = eq == t.columns.end() ? -1 : static_cast<int>(eq - t.columns.begin());
    const bool held = e >= 0 && std::any_of(t.rows.begin(), t.rows.end(),
                                            [e](const auto& row) { return row[e] > 0.5; });
    PlotSeries p{label, {}, {}};
    for (const auto& row : t.rows) {
      if (held && row[e] < 0.5) continue;
      p.x.push_back(row[x]);
      p.y.push_back(row[y]);
    }
    series.push_back(std::move(p));
  }
  return plot_series(series, "nominal strain", "force along the pull (dyn)", "Stretch tests",
                     out_png);
}

}  // namespace knit
