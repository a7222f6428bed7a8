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
#include <map>
#include <sstream>

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

std::string log_header(const Simulator& sim) {
  std::string h =
      "time_s,kinetic_energy,potential_energy,max_violation,contact_pairs,min_contact_distance,"
      "wall_s_per_step";
  for (const auto& term : sim.terms()) h += ",energy_" + std::string(term->name());
  for (const auto& group : sim.model().constraint_groups)
    if (group->kind() != "length")
      for (const char* axis : {"_fx", "_fy", "_fz"}) h += "," + group->name() + axis;
  return h;
}

namespace {

nlohmann::json vec_json(const Eigen::Vector3d& v) {
  return {v[0], v[1], v[2]};
}

// a JSON number, or null where it is not finite
nlohmann::json finite_or_null(double x) {
  return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr);
}

}  // namespace

nlohmann::json constraint_forces_json(const StepData& data) {
  nlohmann::json out = nlohmann::json::object();
  for (const ConstraintRecord& c : data.constraints) {
    if (c.kind == "length") continue;
    out[c.name] = {{"kind", c.kind},
                   {"rows", c.rows},
                   {"force", vec_json(c.force)},
                   {"torque", vec_json(c.torque)},
                   {"about", vec_json(c.about)},
                   {"max_violation", c.max_violation}};
  }
  return out;
}

RunReport run_simulation(Simulator& sim, State& state, const RunOptions& opt) {
  namespace fs = std::filesystem;
  const bool write = !opt.out_dir.empty();
  const fs::path dir(opt.out_dir);
  if (write) {
    fs::create_directories(dir);
    if (opt.write_frames) fs::create_directories(dir / "frames");
  }
  const Model& model = sim.model();
  const double h = model.params.solver.time_step;
  const StepData& data = sim.data();

  // the log grows row by row so long runs can be followed (tail -f DIR/log.csv)
  std::ofstream log;
  if (write) {
    log.open(dir / "log.csv", std::ios::trunc);
    if (!log) throw std::runtime_error((dir / "log.csv").string() + ": cannot open for writing");
    log << log_header(sim) << "\n" << std::setprecision(10);
  }

  RunReport report;
  const long long total_steps = std::max<long long>(0, std::llround(opt.duration / h));
  const auto t0 = Clock::now();
  auto last_progress = t0;
  auto last_output = t0;
  long long last_output_step = 0;
  int frame = 0;
  double contact_pairs_sum = 0;
  long long contact_samples = 0;
  double min_d = std::numeric_limits<double>::infinity();
  std::map<std::string, long long> warnings;
  const bool tty = isatty(fileno(stderr));
  bool printed_progress = false;

  auto write_output = [&]() {
    const double wall = seconds_since(last_output);
    const long long dsteps = report.steps - last_output_step;
    if (write) {
      log << state.time << "," << data.kinetic_energy << "," << data.potential_energy << ","
          << data.max_violation << ","
          << (data.contact.present ? data.contact.point_pairs_in_contact : 0) << ","
          << (data.contact.present && std::isfinite(data.contact.min_distance_ratio)
                  ? data.contact.min_distance_ratio
                  : -1)
          << "," << (dsteps > 0 ? wall / dsteps : 0.0);
      for (const TermRecord& t : data.terms) log << "," << t.energy;
      for (const auto& group : model.constraint_groups) {
        if (group->kind() == "length") continue;
        const ConstraintRecord* c = data.constraint(group->name());
        const Eigen::Vector3d f = c ? c->force : Eigen::Vector3d::Zero();
        log << "," << f[0] << "," << f[1] << "," << f[2];
      }
      log << "\n" << std::flush;
      if (opt.write_frames)
        write_state_file((dir / "frames" / frame_name(frame)).string(),
                         make_state_file(model, state));
    }
    ++frame;
    last_output = Clock::now();
    last_output_step = report.steps;
    if (opt.on_output) opt.on_output(data, state);
  };

  // start on the constraints (glued ends laid apart, pins given off the yarn, …)
  const ProjectionResult initial = sim.satisfy_constraints(state);
  if (!initial.converged) {
    report.status = StepStatus::PROJECTION_FAILED;
    report.message = "the initial state cannot be brought onto the constraints (max |C| = " +
                     std::to_string(initial.max_violation) +
                     "): check pins and glue for conflicting targets";
  }
  sim.forward(state);
  write_output();
  bool stopped_early = false;
  while (report.status == StepStatus::OK && report.steps < total_steps) {
    const StepResult res = sim.step(state, h);
    if (!res.ok()) {
      report.status = res.status;
      report.message = res.message;
      break;
    }
    ++report.steps;
    if (data.contact.present) {
      contact_pairs_sum += static_cast<double>(data.contact.point_pairs_in_contact);
      ++contact_samples;
      min_d = std::min(min_d, data.contact.min_distance_ratio);
    }
    for (const std::string& w : data.warnings) ++warnings[w.substr(0, w.find(" ("))];
    if (report.steps % opt.output_every == 0 || report.steps == total_steps) {
      write_output();
      if (opt.stop_when && opt.stop_when(data, state)) {
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
                << "  t = " << std::fixed << std::setprecision(4) << data.time << " s  "
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
  if (write) {
    write_state_file((dir / "final.kstate").string(), make_state_file(model, state));
    if (report.status != StepStatus::OK)
      write_state_file((dir / "last_good.kstate").string(), make_state_file(model, state));
    log.close();
  }

  // data describes `state`: a failed step leaves both as they were before it
  nlohmann::json s;
  s["status"] = status_word(report.status);
  if (!report.message.empty()) s["message"] = report.message;
  s["stopped_early"] = stopped_early;
  s["steps"] = report.steps;
  s["time_step_s"] = h;
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
  s["max_constraint_violation"] = data.max_violation;
  s["kinetic_energy"] = data.kinetic_energy;
  s["potential_energy"] = data.potential_energy;
  nlohmann::json energies = nlohmann::json::object();
  for (const TermRecord& t : data.terms) energies[t.name] = t.energy;
  s["energies"] = energies;
  if (contact_samples > 0) {
    s["contact_pairs_mean"] = contact_pairs_sum / contact_samples;
    s["min_contact_distance"] = finite_or_null(min_d);
  }
  s["constraint_forces"] = constraint_forces_json(data);
  nlohmann::json stages = nlohmann::json::object();
  for (const auto& [name, sec] : data.stage_seconds) stages[name] = sec;
  s["stage_seconds"] = stages;
  if (!warnings.empty()) {
    nlohmann::json w = nlohmann::json::object();
    for (const auto& [text, count] : warnings) w[text] = count;
    s["warnings"] = w;  // steps with each warning
  }
  s["us_per_segment_step"] =
      report.steps > 0 ? 1e6 * wall / (static_cast<double>(report.steps) * model.num_seg()) : 0.0;
  s["frames_written"] = write && opt.write_frames ? frame : 0;
  for (const auto& [key, value] : opt.extra.items()) s[key] = value;
  if (opt.on_finish) opt.on_finish(sim, state, s);
  if (write) write_file_atomic((dir / "summary.json").string(), s.dump(2) + "\n");
  report.summary = s;
  return report;
}

}  // namespace knit
