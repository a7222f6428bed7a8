#include "knit/solver/runner.hpp"

#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/task_arena.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <sstream>

#include "knit/contact/contact_term.hpp"
#include "knit/io/state_file.hpp"

namespace knit {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

std::string frame_name(int index) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "state_%06d.kstate", index);
  return buf;
}

std::string format_duration(double s) {
  std::ostringstream o;
  if (s < 60)
    o << std::fixed << std::setprecision(0) << s << " s";
  else if (s < 3600)
    o << static_cast<int>(s / 60) << " min " << static_cast<int>(std::fmod(s, 60)) << " s";
  else
    o << std::fixed << std::setprecision(1) << s / 3600 << " h";
  return o.str();
}

}  // namespace

ContactReport contact_report(const Simulator& sim) {
  const auto* contact = dynamic_cast<const ContactTerm*>(sim.find_term("contact"));
  if (!contact) return {};
  const ContactStats& st = contact->last_stats();
  return {true, st.point_pairs_in_contact, st.min_distance_ratio};
}

RunReport run_simulation(Simulator& sim, State& state, const RunOptions& opt) {
  namespace fs = std::filesystem;
  const fs::path dir(opt.out_dir);
  fs::create_directories(dir);
  if (opt.write_frames) fs::create_directories(dir / "frames");
  const Model& model = sim.model();

  // the log grows row by row so long runs can be followed (tail -f DIR/log.csv)
  std::ofstream log(dir / "log.csv", std::ios::trunc);
  if (!log) throw std::runtime_error((dir / "log.csv").string() + ": cannot open for writing");
  log << "time_s,kinetic_energy,potential_energy,max_violation,contact_pairs,min_contact_distance,"
         "wall_s_per_step\n";
  log << std::setprecision(10);

  RunReport report;
  const long long total_steps = std::max<long long>(0, std::llround(opt.duration / opt.time_step));
  const auto t0 = Clock::now();
  auto last_progress = t0;
  auto last_output = t0;
  long long last_output_step = 0;
  int frame = 0;
  double contact_pairs_sum = 0;
  long long contact_samples = 0;
  double min_d = std::numeric_limits<double>::infinity();
  const bool tty = isatty(fileno(stderr));
  bool printed_progress = false;

  auto write_output = [&]() {
    const double wall = seconds_since(last_output);
    const long long dsteps = report.steps - last_output_step;
    const ContactReport cr = contact_report(sim);
    log << state.time << "," << sim.kinetic_energy(state) << "," << sim.potential_energy(state)
        << "," << sim.max_violation(state) << "," << (cr.present ? cr.pairs_in_contact : 0) << ","
        << (cr.present && std::isfinite(cr.min_distance_ratio) ? cr.min_distance_ratio : -1) << ","
        << (dsteps > 0 ? wall / dsteps : 0.0) << "\n"
        << std::flush;
    if (opt.write_frames)
      write_state_file((dir / "frames" / frame_name(frame)).string(),
                       make_state_file(model, state));
    ++frame;
    last_output = Clock::now();
    last_output_step = report.steps;
  };

  // start on the constraints (glued ends laid apart, pins given off the yarn, …)
  const ProjectionResult initial = sim.satisfy_constraints(state);
  if (!initial.converged) {
    report.status = StepStatus::PROJECTION_FAILED;
    report.message = "the initial state cannot be brought onto the constraints (max |C| = " +
                     std::to_string(initial.max_violation) +
                     "): check pins and glue for conflicting targets";
  }
  write_output();
  bool stopped_early = false;
  while (report.status == StepStatus::OK && report.steps < total_steps) {
    const StepResult res = sim.step(state, opt.time_step);
    if (!res.ok()) {
      report.status = res.status;
      report.message = res.message;
      break;
    }
    ++report.steps;
    const ContactReport cr = contact_report(sim);
    if (cr.present) {
      contact_pairs_sum += static_cast<double>(cr.pairs_in_contact);
      ++contact_samples;
      min_d = std::min(min_d, cr.min_distance_ratio);
    }
    if (report.steps % opt.output_every == 0 || report.steps == total_steps) {
      write_output();
      if (opt.stop_when && opt.stop_when(sim, state)) {
        stopped_early = true;
        break;
      }
    }
    if (opt.progress && seconds_since(last_progress) > (tty ? 0.5 : 15.0) &&
        seconds_since(t0) > 2.0) {
      const double elapsed = seconds_since(t0);
      const double rate = report.steps / elapsed;
      const double left = (total_steps - report.steps) / std::max(rate, 1e-9);
      std::cerr << (tty ? "\r" : "") << "step " << report.steps << "/" << total_steps
                << "  t = " << std::fixed << std::setprecision(4) << state.time << " s  "
                << std::setprecision(1) << rate << " steps/s  ~" << format_duration(left)
                << " left   " << (tty ? "" : "\n") << std::flush;
      std::cerr.unsetf(std::ios::floatfield);
      last_progress = Clock::now();
      printed_progress = true;
    }
  }
  if (printed_progress && tty) std::cerr << "\n";
  const double wall = seconds_since(t0);

  // outputs: the final (or last good) state, the log and the summary
  write_state_file((dir / "final.kstate").string(), make_state_file(model, state));
  if (report.status != StepStatus::OK)
    write_state_file((dir / "last_good.kstate").string(), make_state_file(model, state));
  log.close();

  nlohmann::json s;
  s["status"] = status_word(report.status);
  if (!report.message.empty()) s["message"] = report.message;
  s["stopped_early"] = stopped_early;
  s["steps"] = report.steps;
  s["time_step_s"] = opt.time_step;
  s["sim_time_s"] = state.time;
  s["wall_time_s"] = wall;
  s["threads"] = std::min<size_t>(
      tbb::this_task_arena::max_concurrency(),
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  s["yarns"] = model.yarns.size();
  s["segments"] = model.num_seg();
  s["control_points"] = model.num_cp();
  s["yarn_length_cm"] = model.total_length();
  s["max_length_violation"] = FastProjection::max_length_violation(model, state.q);
  s["max_constraint_violation"] = sim.max_violation(state);
  s["kinetic_energy"] = sim.kinetic_energy(state);
  s["potential_energy"] = sim.potential_energy(state);
  if (contact_samples > 0) {
    s["contact_pairs_mean"] = contact_pairs_sum / contact_samples;
    s["min_contact_distance"] =
        std::isfinite(min_d) ? nlohmann::json(min_d) : nlohmann::json(nullptr);
  }
  nlohmann::json stages = nlohmann::json::object();
  for (const auto& [name, sec] : sim.stage_seconds()) stages[name] = sec;
  s["stage_seconds"] = stages;
  s["us_per_segment_step"] =
      report.steps > 0 ? 1e6 * wall / (static_cast<double>(report.steps) * model.num_seg()) : 0.0;
  s["frames_written"] = opt.write_frames ? frame : 0;
  for (const auto& [key, value] : opt.extra.items()) s[key] = value;
  if (opt.on_finish) opt.on_finish(sim, state, s);
  write_file_atomic((dir / "summary.json").string(), s.dump(2) + "\n");
  report.summary = s;
  return report;
}

}  // namespace knit
