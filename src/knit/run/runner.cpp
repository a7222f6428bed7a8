#include "knit/run/runner.hpp"

#include "knit/objects/object.hpp"

#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/task_arena.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <sstream>

#include "knit/contact/crossings.hpp"
#include "knit/io/state_file.hpp"
#include "knit/run/interrupt.hpp"
#include "knit/run/step_halving.hpp"
#include "knit/util/atomic_file.hpp"
#include "knit/util/input_file.hpp"
#include "knit/util/run_dir.hpp"

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
      "wall_s_per_step,force_residual";
  for (const auto& term : sim.terms()) h += ",energy_" + std::string(term->name());
  for (const auto& group : sim.model().constraint_groups)
    if (group->kind() != "length")
      for (const char* axis : {"_fx", "_fy", "_fz"}) h += "," + group->name() + axis;
  for (const auto& object : sim.model().objects)
    for (const char* col : {"_contacts", "_penetration", "_fx", "_fy", "_fz"})
      h += "," + object->name + col;
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

namespace {
// closest approach (fraction of the contact distance 2r) a run may start from
constexpr double MIN_START_DISTANCE_RATIO = 0.05;
}  // namespace

double next_step_length(double time, double end_time, double h) {
  // the time is a sum of steps: after 10⁴–10⁶ of them its rounding error reaches 1e-12 s,
  // so "exactly h left" is judged to a millionth of a step
  constexpr double SNAP = 1e-6;
  const double left = end_time - time;
  if (left <= SNAP * h) return 0;
  if (left > 1.5 * h) return h;
  if (std::abs(left - h) <= SNAP * h) return h;
  if (left <= h) return left;
  return 0.5 * left;  // (h, 1.5 h]: two steps in (h/2, 3h/4] rather than one of h and a sliver
}

nlohmann::json params_json(const Params& p) {
  // grouped as params.def declares them
  nlohmann::json j = {{"material", nlohmann::json::object()},
                      {"discretisation", nlohmann::json::object()},
                      {"solver", nlohmann::json::object()}};
  for (const ParamDecl& d : param_table()) j[d.group][d.name] = param_json(d, p);
  j["gravity"] = vec_json(p.gravity);
  return j;
}

const char* knitsim_version() {
  return KNIT_VERSION;
}

namespace {

// drops the rows of an existing log.csv whose time is after `time` (a run resumed from an
// earlier state of the same directory goes on from there), and the row at `time` unless
// `keep_at_time` (the state is at an output step: an older knitsim also wrote a row at an
// interrupt between two, which the uninterrupted run does not have). A row's time is
// written with 10 significant digits: "at `time`" is within LOG_TIME_TOLERANCE of it, far
// less than a step apart (rows are a step apart at least: 1e-9 of the time is a step only
// after a billion steps)
// (returns false, touching nothing, when its header is not `expected`: an older version
// wrote other columns)
bool truncate_log_after(const std::filesystem::path& path, double time, bool keep_at_time,
                        const std::string& expected) {
  std::ifstream in(path);
  if (!in) return false;
  std::string line, kept;
  bool header = true;
  while (std::getline(in, line)) {
    if (header && line != expected) return false;
    if (!header) {
      const double t = std::strtod(line.c_str(), nullptr);
      constexpr double LOG_TIME_TOLERANCE = 1e-9;  // relative; the rows' 10 digits round by 5e-10
      const double tol = LOG_TIME_TOLERANCE * std::abs(time) + 1e-15;
      if (keep_at_time ? t > time + tol : t >= time - tol) break;
    }
    header = false;
    kept += line + "\n";
  }
  in.close();
  write_file_atomic(path.string(), kept);
  return true;
}

// adds a step's records to the run's totals (`objects`: the totals of the model's objects,
// in its order)
void add_step(RunTotals& t, const std::vector<RunTotals::Object*>& objects, const StepData& data,
              double step, double h) {
  ++t.steps;
  if (step != h) t.shortened_steps.push_back(step);
  if (data.contact.present) {
    ++t.contact_steps;
    t.contact_pairs_sum += static_cast<double>(data.contact.point_pairs_in_contact);
    t.min_contact_distance = std::min(t.min_contact_distance, data.contact.min_distance_ratio);
    t.contact_linearised += data.contact.linearised;
  }
  t.matrix_kept += data.matrix_kept;
  t.reuse_scale_sum += data.reuse_scale;
  if (data.solve_iterations > 0) {
    ++t.solve_steps;
    t.solve_iterations += data.solve_iterations;
    t.solve_iterations_max = std::max(t.solve_iterations_max, data.solve_iterations);
    t.solve_residual_max = std::max(t.solve_residual_max, data.solve_residual);
  }
  for (size_t o = 0; o < data.objects.size() && o < objects.size(); ++o) {
    objects[o]->deepest_penetration =
        std::max(objects[o]->deepest_penetration, data.objects[o].deepest_penetration);
    objects[o]->contact_points_sum += static_cast<double>(data.objects[o].points_in_contact);
  }
  for (const std::string& w : data.warnings) ++t.warnings[w.substr(0, w.find(" ("))];
  if (data.friction.present) {
    ++t.friction_steps;
    t.friction_pairs += data.friction.pairs;
    t.friction_stuck += data.friction.stuck;
    t.friction_passes += data.friction.passes;
    t.friction_passes_max = std::max(t.friction_passes_max, data.friction.passes);
    t.friction_work += data.friction.work;
  }
}

// The wall-clock figures of a run's earlier legs, as the summary they left in its
// directory says (zero where it says nothing): they stay out of the state files, whose
// bytes then depend on what the run computes alone.
struct WallFigures {
  double wall_s = 0;
  std::map<std::string, double> stage_seconds;
  long long checkpoints = 0;
};

WallFigures read_wall_figures(const std::filesystem::path& summary) {
  WallFigures w;
  std::ifstream in(summary);
  if (!in) return w;
  const nlohmann::json s = nlohmann::json::parse(in, nullptr, false);
  if (!s.is_object()) return w;
  auto seconds = [](const nlohmann::json& v) {
    return v.is_number() && std::isfinite(v.get<double>()) && v.get<double>() >= 0 ? v.get<double>()
                                                                                   : 0.0;
  };
  if (s.contains("wall_time_s")) w.wall_s = seconds(s["wall_time_s"]);
  if (s.contains("stage_seconds") && s["stage_seconds"].is_object())
    for (const auto& [name, sec] : s["stage_seconds"].items()) w.stage_seconds[name] = seconds(sec);
  if (s.contains("checkpoints_written") && s["checkpoints_written"].is_number_integer())
    w.checkpoints = std::max(0LL, s["checkpoints_written"].get<long long>());
  return w;
}

// bytes of one frame file for this model (positions, velocities, stitches, knit block, the
// run's totals)
double frame_bytes(const Model& model) {
  double b = 64 + 12.0 * model.yarns.size() + 48.0 * model.num_cp();
  b += 1024 + 128.0 * model.objects.size();  // (the totals: about 700 bytes of JSON)
  if (model.has_stitches()) b += 8.0 * model.num_seg();
  // (the knit's description, with its relaxation's settings, is about 550 bytes of JSON)
  if (model.knit)
    b += 1024 + static_cast<double>(model.knit->pattern.size()) + 8.0 * model.num_seg() +
         56.0 * model.glues.size();
  return b;
}

}  // namespace

void check_start(Simulator& sim, const State& state) {
  sim.forward(state);
  const StepData& data = sim.data();
  const Model& model = sim.model();
  // yarns that start inside each other (two copies of a yarn, a yarn laid through another)
  // have no direction to be pushed apart: say so instead of letting the run blow up
  if (data.contact.present && data.contact.min_distance_ratio < MIN_START_DISTANCE_RATIO) {
    const ContactPairRecord* worst = nullptr;
    for (const ContactPairRecord& p : data.contact.pairs)
      if (!worst || p.d < worst->d) worst = &p;
    std::ostringstream msg;
    msg << "the yarns start inside each other";
    if (worst) {
      const int yi = model.seg_yarn[worst->seg_i], yj = model.seg_yarn[worst->seg_j];
      msg << ": segment " << worst->seg_i - model.yarns[yi].seg_begin << " of yarn " << yi
          << " and segment " << worst->seg_j - model.yarns[yj].seg_begin << " of yarn " << yj
          << " are " << std::setprecision(3) << worst->d * 2 * model.params.material.radius
          << " cm apart, less than " << MIN_START_DISTANCE_RATIO * 100
          << " % of a yarn diameter (are two yarns at the same place?)";
    }
    throw std::invalid_argument(msg.str());
  }
  // a yarn whose centreline starts inside a solid object would be thrown out of it by the
  // penalty (or pushed out slowly by the filter) through whatever is in the way
  for (const auto& object : model.objects) {
    const ObjectFrame frame(*object, state.time);
    for (int i = 0; i < model.num_seg(); ++i) {
      Eigen::Vector3d centre;
      double rho;
      segment_ball(model, state.q, i, centre, rho);
      if (frame.ball_outside(centre, rho, 0)) continue;
      for (int k = 0; k <= 8; ++k) {
        const Eigen::Vector3d y = point_position(model, state.q, {i, k / 8.0});
        const double phi = frame.distance(y, nullptr);
        if (phi < 0) {
          const int yarn = model.seg_yarn[i];
          std::ostringstream msg;
          msg << "segment " << i - model.yarns[yarn].seg_begin << " of yarn " << yarn
              << " starts inside object \"" << object->name << "\" (" << std::setprecision(3)
              << -phi << " cm below its surface, at (" << y.x() << ", " << y.y() << ", " << y.z()
              << ")): place the yarn outside the objects";
          throw std::invalid_argument(msg.str());
        }
      }
    }
  }
}

RunReport run_simulation(Simulator& sim, State& state, const RunOptions& opt) {
  namespace fs = std::filesystem;
  const Model& model = sim.model();
  const double h = model.params.solver.time_step;
  // everything is checked before anything is written
  validate_params(model.params);
  if (!std::isfinite(state.time) || state.time < 0)
    throw std::invalid_argument("the state's time is " + short_number(state.time) +
                                " s (expected a finite time >= 0)");
  if (!state.q.allFinite() || !state.v.allFinite())
    throw std::invalid_argument("the state holds positions or velocities that are not finite");
  if (opt.output_every < 1)
    throw std::invalid_argument("output_every = " + std::to_string(opt.output_every) +
                                " (expected at least 1 step between written states)");
  if (!(opt.checkpoint_every_s >= 0) || !std::isfinite(opt.checkpoint_every_s))
    throw std::invalid_argument("checkpoint_every_s = " + short_number(opt.checkpoint_every_s) +
                                " (expected wall seconds >= 0; 0: no checkpoints)");
  const bool by_end_time = std::isfinite(opt.end_time);
  double end_time = by_end_time ? opt.end_time : state.time + opt.duration;
  if (by_end_time) {
    if (!(opt.end_time > state.time - 1e-6 * h))
      throw std::invalid_argument(
          "the run should end at t = " + short_number(opt.end_time) +
          " s, but its state is already at t = " + short_number(state.time) + " s");
    if (opt.end_time - state.time > MAX_DURATION) check_duration(opt.end_time - state.time, h);
  } else {
    check_duration(opt.duration, h);
  }
  // the end the run was going to, where a resumed run asks for it (give or take rounding)
  const bool resumed_totals = opt.continue_in_place && opt.resumed_totals.has_value();
  if (resumed_totals && std::abs(opt.resumed_totals->end_time - end_time) <= 1e-6 * h)
    end_time = opt.resumed_totals->end_time;
  const long long first_step = std::llround(state.time / h);  // global step index
  const long long total_steps =
      static_cast<long long>(std::ceil((end_time - state.time) / h - 1e-6));
  const bool write = !opt.out_dir.empty();
  const fs::path dir(opt.out_dir);
  RunDirectory held;  // locked while the run writes it (a recipe may hold it already)
  if (write) {
    // the frames must fit on the disk (a long run with frequent frames can fill it)
    const double frames = opt.write_frames ? std::floor(total_steps / opt.output_every) + 2 : 2;
    const double bytes = frames * frame_bytes(model) + 200.0 * frames;
    std::error_code ec;
    fs::path probe = dir;
    while (!probe.empty() && !fs::exists(probe, ec)) probe = probe.parent_path();
    const fs::space_info space = fs::space(probe.empty() ? fs::path(".") : probe, ec);
    if (!ec && bytes > static_cast<double>(space.available))
      throw std::invalid_argument("the run would write about " + format_bytes(bytes) + " (" +
                                  std::to_string(static_cast<long long>(frames)) +
                                  " states) into " + opt.out_dir + ", and its disk has " +
                                  format_bytes(static_cast<double>(space.available)) +
                                  " free: write fewer states (a larger output interval) or none");
    if (bytes > 2e9)
      std::cerr << "knitsim: warning: this run will write about " << format_bytes(bytes) << " into "
                << opt.out_dir << "\n";
    held = opt.continue_in_place ? continue_run_directory(opt.out_dir)
                                 : prepare_run_directory(opt.out_dir, false);
    if (opt.write_frames) {
      fs::create_directories(dir / "frames");
      claim_run_output((dir / "frames").string());
    }
  }
  const StepData& data = sim.data();

  // the log grows row by row so long runs can be followed (tail -f DIR/log.csv)
  std::ofstream log;
  if (write) {
    bool appending = false;
    if (opt.continue_in_place && fs::exists(dir / "log.csv")) {
      appending = truncate_log_after(dir / "log.csv", state.time,
                                     first_step % opt.output_every == 0, log_header(sim));
      // a log of other columns (an older knitsim) is kept whole beside the new one
      if (!appending) {
        claim_run_output((dir / "log_before_resume.csv").string());
        fs::rename(dir / "log.csv", dir / "log_before_resume.csv");
      }
    }
    claim_run_output((dir / "log.csv").string());
    if (appending) {
      log.open(dir / "log.csv", std::ios::app);
    } else {
      log.open(dir / "log.csv", std::ios::trunc);
      if (log) log << log_header(sim) << "\n";
    }
    if (!log) throw std::runtime_error((dir / "log.csv").string() + ": cannot open for writing");
    log << std::setprecision(10);
  }

  RunReport report;
  const auto t0 = Clock::now();
  auto last_progress = t0;
  auto last_output = t0;
  auto last_checkpoint = t0;
  // what the run adds up: from the resumed state's totals when the run goes on in its
  // directory (one run, however often stopped), else from nothing at this state
  RunTotals totals;
  totals.start_time = state.time;
  if (resumed_totals) totals = *opt.resumed_totals;
  totals.end_time = end_time;
  // and the earlier legs' wall-clock figures, from the summary they left
  const WallFigures earlier =
      resumed_totals && write ? read_wall_figures(dir / "summary.json") : WallFigures{};
  const double leg_start_time = state.time;
  const long long leg_first_step = totals.steps;
  long long last_output_steps = totals.steps;
  long long step_index = first_step;
  long long leg_checkpoints = 0;
  std::vector<RunTotals::Object*> object_totals;  // per object of the model, in its order
  for (const auto& object : model.objects) object_totals.push_back(&totals.objects[object->name]);
  HalvingStepper stepper(model.params.solver.max_step_halvings, opt.halving_calm_steps,
                         totals.halving);
  const bool tty = isatty(fileno(stderr));
  bool printed_progress = false;

  // the command that goes on from DIR/final.kstate with the time left
  auto resume_command = [&] {
    std::string cmd = opt.resume_command;
    if (const size_t at = cmd.find("{time_left}"); at != std::string::npos)
      cmd.replace(at, 11, time_left_text(state.time, end_time, h));
    return cmd;
  };
  // what every summary says of where the run stands (the end's and a checkpoint's)
  auto where_the_run_is = [&](nlohmann::json& j) {
    j["knitsim_version"] = knitsim_version();
    j["steps"] = totals.steps;
    j["time_step_s"] = h;
    j["end_time_s"] = end_time;
    j["sim_time_s"] = state.time;
  };
  // the wall-clock figures, summed over the run's legs (the end's summary and a
  // checkpoint's: the next leg reads them back)
  auto wall_figures = [&](nlohmann::json& j) {
    const double wall = earlier.wall_s + seconds_since(t0);
    j["wall_time_s"] = wall;
    // wall seconds per simulated second (where the totals start: see totals_since_s)
    if (state.time > totals.start_time)
      j["wall_s_per_simulated_s"] = wall / (state.time - totals.start_time);
    j["us_per_segment_step"] =
        totals.steps > 0 ? 1e6 * wall / (static_cast<double>(totals.steps) * model.num_seg()) : 0.0;
    std::map<std::string, double> stages = earlier.stage_seconds;
    for (const auto& [name, sec] : data.stage_seconds) stages[name] += sec;
    j["stage_seconds"] = stages;
    if (const long long n = earlier.checkpoints + leg_checkpoints; n > 0)
      j["checkpoints_written"] = n;
  };
  // a state as the run writes it: with its totals up to the state
  auto run_state_file = [&] {
    StateFile f = make_state_file(model, state);
    totals.halving = stepper.counts();
    f.run = totals;
    return f;
  };
  // a run without frames keeps its latest state on disk (RunOptions::checkpoint_every_s);
  // each file is replaced atomically, the state first: a kill between the two leaves the
  // previous checkpoint's summary, whose command then runs one interval past the end
  auto write_checkpoint = [&] {
    write_state_file((dir / "final.kstate").string(), run_state_file());
    ++leg_checkpoints;
    nlohmann::json c;
    c["status"] = "running";
    c["message"] = "a checkpoint at t = " + short_number(state.time) + " s, " +
                   format_duration(seconds_since(t0)) +
                   " into the run: if no knitsim is running in this directory, the run was "
                   "stopped without writing its end; it goes on from final.kstate";
    if (!opt.resume_command.empty()) c["resume_command"] = resume_command();
    where_the_run_is(c);
    wall_figures(c);
    for (const auto& [key, value] : opt.extra.items()) c[key] = value;
    write_file_atomic((dir / "summary.json").string(), c.dump(2) + "\n");
    last_checkpoint = Clock::now();
  };

  // at an output step: the measurements, the log row and (when `frame`) a frame; at an
  // interrupt between two output steps the measurements alone (its state goes into
  // final.kstate), so that the log has the rows of the uninterrupted run
  auto write_output = [&](bool output_step) {
    sim.forward(state);  // whole records (the steps' own are lean: below)
    if (opt.before_output) opt.before_output(sim, state);
    if (output_step) {
      if (write) {
        const double wall = seconds_since(last_output);
        const long long dsteps = totals.steps - last_output_steps;
        log << state.time << "," << data.kinetic_energy << "," << data.potential_energy << ","
            << data.max_violation << ","
            << (data.contact.present ? data.contact.point_pairs_in_contact : 0) << ","
            << (data.contact.present && std::isfinite(data.contact.min_distance_ratio)
                    ? data.contact.min_distance_ratio
                    : -1)
            << "," << (dsteps > 0 ? wall / static_cast<double>(dsteps) : 0.0) << ","
            << (std::isfinite(data.force_residual) ? data.force_residual : -1);
        for (const TermRecord& t : data.terms) log << "," << t.energy;
        for (const auto& group : model.constraint_groups) {
          if (group->kind() == "length") continue;
          const ConstraintRecord* c = data.constraint(group->name());
          const Eigen::Vector3d f = c ? c->force : Eigen::Vector3d::Zero();
          log << "," << f[0] << "," << f[1] << "," << f[2];
        }
        for (size_t o = 0; o < model.objects.size(); ++o) {
          const ObjectRecord rec = o < data.objects.size() ? data.objects[o] : ObjectRecord{};
          log << "," << rec.points_in_contact << "," << rec.deepest_penetration << ","
              << rec.force[0] << "," << rec.force[1] << "," << rec.force[2];
        }
        log << "\n" << std::flush;
        if (opt.write_frames) {
          // frames are numbered by the global step (a resumed run goes on with the numbers);
          // a last state between two output steps takes the next number
          const long long index = (step_index + opt.output_every - 1) / opt.output_every;
          ++totals.frames_written;  // (counted in the frame's own totals)
          write_state_file((dir / "frames" / frame_name(static_cast<int>(index))).string(),
                           run_state_file());
        }
      }
      last_output = Clock::now();
      last_output_steps = totals.steps;
    }
    if (opt.on_output) opt.on_output(data, state);
  };

  // start on the constraints (glued ends laid apart, pins given off the yarn, …)
  const ProjectionResult initial = sim.satisfy_constraints(state);
  if (!initial.converged) {
    report.status = StepStatus::PROJECTION_FAILED;
    report.message = "the initial state cannot be brought onto the constraints (max |C| = " +
                     short_number(initial.max_violation) +
                     "): check pins and glue for conflicting targets";
  }
  sim.forward(state);
  if (report.status == StepStatus::OK) check_start(sim, state);
  if (opt.continue_in_place) {
    // the directory already holds this state's row and frame
    if (opt.on_output) opt.on_output(data, state);
  } else {
    write_output(true);
  }
  bool stopped_early = false;
  int signal = 0;
  // the loop reads whole records at its outputs alone: the steps may leave out what only
  // records read (Simulator::set_lean_records), as they were once the loop ends
  struct LeanRecords {
    Simulator& sim;
    bool was;
    ~LeanRecords() { sim.set_lean_records(was); }
  } lean{sim, sim.lean_records()};
  sim.set_lean_records(true);
  // a model that refuses crossings has had every step it took checked by the simulator
  // (each substep of a halved one): none can have crossed, and none is checked twice
  const bool refused = model.params.solver.refuse_crossings;
  Eigen::VectorXd q_before;
  auto check_crossings = [&](double t_before) {
    CrossingTotals& c = totals.crossings;
    ++c.steps_checked;
    if (refused) return;
    const std::vector<SegmentCrossing> found = find_crossings(model, q_before, state.q);
    c.count += static_cast<long long>(found.size());
    for (const SegmentCrossing& x : found) {
      const double t = t_before + x.step_fraction * (state.time - t_before);
      if (t >= c.first_time) continue;
      c.first_time = t;
      c.first_segment_a = x.segment_a;
      c.first_segment_b = x.segment_b;
      c.first_x = x.point.x();
      c.first_y = x.point.y();
      c.first_z = x.point.z();
    }
  };
  while (report.status == StepStatus::OK) {
    const double hs = next_step_length(state.time, end_time, h);
    if (hs == 0) break;
    if (opt.check_crossings && !refused) q_before = state.q;
    const double t_before = state.time;
    const StepResult res = stepper.step(sim, state, hs);
    if (res.ok() && opt.check_crossings) check_crossings(t_before);
    if (!res.ok()) {
      report.status = res.status;
      report.message = res.message;
      break;
    }
    ++step_index;
    add_step(totals, object_totals, data, hs, h);
    signal = interrupt_signal();
    const bool last = next_step_length(state.time, end_time, h) == 0;
    const bool output_step = step_index % opt.output_every == 0 || last;
    if (output_step || signal != 0) {
      write_output(output_step);
      if (output_step && opt.stop_when && opt.stop_when(data, state)) {
        stopped_early = true;
        break;
      }
      if (output_step && write && !opt.write_frames && opt.checkpoint_every_s > 0 && !last &&
          signal == 0 && seconds_since(last_checkpoint) >= opt.checkpoint_every_s)
        write_checkpoint();
    }
    // a signal during the last step comes when the run is done: it ends as asked (an
    // interrupted run would leave a resume command with no time left to run)
    if (signal != 0 && !last) {
      report.status = StepStatus::INTERRUPTED;
      report.message = std::string("interrupted by ") + interrupt_signal_name(signal) +
                       " at t = " + short_number(state.time) + " s";
      break;
    }
    if (opt.progress && seconds_since(last_progress) > (tty ? 0.5 : 15.0) &&
        seconds_since(t0) > 2.0) {
      const double elapsed = seconds_since(t0);
      const long long leg_steps = totals.steps - leg_first_step;
      const double rate = static_cast<double>(leg_steps) / elapsed;
      const double left = static_cast<double>(total_steps - leg_steps) / std::max(rate, 1e-9);
      std::cerr << (tty ? "\r" : "") << "step " << leg_steps << "/" << total_steps
                << "  t = " << std::fixed << std::setprecision(4) << data.time << " s  "
                << std::setprecision(1) << rate << " steps/s  ~" << format_duration(left)
                << " left   " << (tty ? "" : "\n") << std::flush;
      std::cerr.unsetf(std::ios::floatfield);
      last_progress = Clock::now();
      printed_progress = true;
    }
  }
  if (printed_progress && tty) std::cerr << "\n";
  const bool failed = report.status != StepStatus::OK && report.status != StepStatus::INTERRUPTED;
  report.steps = totals.steps;

  // outputs: the final (or last good) state, the log and the summary
  if (write) {
    write_state_file((dir / "final.kstate").string(), run_state_file());
    if (failed)
      write_state_file((dir / "last_good.kstate").string(), run_state_file());
    else
      fs::remove(dir / "last_good.kstate");
    log.close();
  }

  // data describes `state`: a failed step leaves both as they were before it
  sim.forward(state);  // (whole records)
  nlohmann::json s;
  s["status"] = status_word(report.status);
  if (!report.message.empty()) s["message"] = report.message;
  if (report.status != StepStatus::OK && !opt.resume_command.empty())
    s["resume_command"] = resume_command();
  where_the_run_is(s);
  if (opt.continue_in_place && !resumed_totals) {
    s["totals_since_s"] = leg_start_time;
    s["totals_note"] =
        "resumed from a state written before states carried their run's totals: the steps, "
        "extremes, means and counts cover the run from totals_since_s on";
  }
  s["stopped_early"] = stopped_early;
  if (!totals.shortened_steps.empty()) {
    s["shortened_steps_s"] = totals.shortened_steps;
    s["time_note"] =
        "the duration is not a multiple of the time step: the last steps were "
        "shortened to end at the time asked";
  }
  if (model.params.solver.max_step_halvings > 0)
    s["step_halvings"] = {{"retried", stepper.retried()},
                          {"deepest", stepper.deepest()},
                          {"substeps", stepper.substeps()}};
  wall_figures(s);
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
  s["force_residual"] = finite_or_null(data.force_residual);
  if (std::isfinite(data.force_residual) && data.force_residual_peak.control_point >= 0) {
    // where the state is furthest from rest, and how concentrated the residual is
    const int cp = data.force_residual_peak.control_point;
    const int yarn = model.yarn_of_cp(cp);
    const Eigen::Vector3d at = state.q.segment<3>(3 * cp);
    s["force_residual_peak"] = {{"yarn", yarn},
                                {"control_point", cp - model.yarns[yarn].cp_begin},
                                {"position_cm", {at.x(), at.y(), at.z()}},
                                {"acceleration", data.force_residual_peak.acceleration},
                                {"top_percent_share", data.force_residual_peak.top_share}};
  }
  s["potential_energy"] = data.potential_energy;
  nlohmann::json energies = nlohmann::json::object();
  for (const TermRecord& t : data.terms) energies[t.name] = t.energy;
  s["energies"] = energies;
  const double steps = static_cast<double>(totals.steps);
  if (totals.solve_steps > 0)
    s["implicit_solve"] = {{"steps", totals.solve_steps},
                           {"iterations_mean", static_cast<double>(totals.solve_iterations) /
                                                   static_cast<double>(totals.solve_steps)},
                           {"iterations_max", totals.solve_iterations_max},
                           {"relative_residual_max", totals.solve_residual_max}};
  if (totals.contact_steps > 0) {
    const double n = static_cast<double>(totals.contact_steps);
    s["contact_pairs_mean"] = totals.contact_pairs_sum / n;
    s["min_contact_distance"] = finite_or_null(totals.min_contact_distance);
    if (model.params.solver.contact_reuse > 0)
      s["contact_linearised_fraction"] = static_cast<double>(totals.contact_linearised) / n;
  }
  if (model.params.solver.contact_reuse > 0 && totals.steps > 0) {
    s["matrix_kept_fraction"] = static_cast<double>(totals.matrix_kept) / steps;
    s["contact_reuse_scale_mean"] = totals.reuse_scale_sum / steps;
  }
  s["constraint_forces"] = constraint_forces_json(data);
  if (totals.friction_steps > 0) {
    const double n = static_cast<double>(totals.friction_steps);
    const double pairs = static_cast<double>(totals.friction_pairs);
    s["yarn_friction"] = {
        {"pairs_mean", pairs / n},
        {"stuck_fraction", pairs > 0 ? static_cast<double>(totals.friction_stuck) / pairs : 0.0},
        {"work_erg", totals.friction_work},
        {"passes_mean", static_cast<double>(totals.friction_passes) / n},
        {"passes_max", totals.friction_passes_max}};
  }
  if (!model.objects.empty()) {
    nlohmann::json objects = nlohmann::json::object();
    for (size_t o = 0; o < model.objects.size(); ++o) {
      const ObjectRecord rec = o < data.objects.size() ? data.objects[o] : ObjectRecord{};
      objects[model.objects[o]->name] = {
          {"max_penetration_cm", object_totals[o]->deepest_penetration},
          {"contact_points_mean",
           totals.steps > 0 ? object_totals[o]->contact_points_sum / steps : 0.0},
          {"contact_points", rec.points_in_contact},
          {"force_dyn", vec_json(rec.force)}};
    }
    s["objects"] = objects;
  }
  if (!totals.warnings.empty()) {
    nlohmann::json w = nlohmann::json::object();
    for (const auto& [text, count] : totals.warnings) w[text] = count;
    s["warnings"] = w;  // steps with each warning
  }
  if (opt.check_crossings) {
    const CrossingTotals& c = totals.crossings;
    nlohmann::json first = nullptr;
    if (c.count > 0)
      first = {{"time_s", c.first_time},
               {"segments", {c.first_segment_a, c.first_segment_b}},
               {"yarns", {model.seg_yarn[c.first_segment_a], model.seg_yarn[c.first_segment_b]}},
               {"point_cm", {c.first_x, c.first_y, c.first_z}}};
    s["crossings"] = {{"steps_checked", c.steps_checked}, {"count", c.count}, {"first", first}};
  }
  s["frames_written"] = totals.frames_written;
  s["params"] = params_json(model.params);
  for (const auto& [key, value] : opt.extra.items()) s[key] = value;
  if (opt.on_finish) opt.on_finish(sim, state, s);
  if (write) write_file_atomic((dir / "summary.json").string(), s.dump(2) + "\n");
  report.summary = s;
  return report;
}

}  // namespace knit
