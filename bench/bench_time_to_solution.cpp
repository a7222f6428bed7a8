// Time to a result: wall seconds per simulated second of a scene (by default the relaxed
// 12×12 stockinette hanging from a clamp with the simulation parameters,
// examples/hanging_knit.json; --knit places another relaxed knit there, e.g. the 42×32),
// for each integrator and time step asked, and how far each run's shape at the end lies
// from a reference run (the explicit step at h = 1/11800 s unless told otherwise): the
// largest control-point distance, in yarn radii, and — for motions that no two step sizes
// follow point by point, such as a scarf folding onto a floor — the distance between the
// centres of the control points and the largest difference of their bounding boxes'
// extents (cm). Each run also reports the closest yarn approach d and the deepest overlap
// of the yarn's tube with an object over all its steps. Runs that go unstable say when;
// runs whose yarns came within half the contact distance (d < 0.5) say so
// (contact_held false): their steps held but their yarns passed or nearly did.
//   bench_time_to_solution [--scene S] [--knit K] [--time T]
//                          [--runs explicit:2e-4,imex:4e-4,...] [--reference explicit:H]
//                          [--threads N] [--end-mass-floor F]
// A run named INTEGRATOR+bending:H takes the bending energy implicitly too
// (SolverSettings::implicit_bending), e.g. imex-contact+bending:3.2e-3; imex-contact+cg:H
// (also imex-contact+bending+cg:H) solves the whole linear system by conjugate gradients
// to 1e-3 of its right-hand side (SolverSettings::contact_solve_tolerance) instead of once
// with the band factor.
// --end-mass-floor: each yarn end's two control points get at least F of an interior one's
// mass (the scene key end_mass_floor): the large steps of imex-contact otherwise fail first
// at the light ends.
#include <CLI/CLI.hpp>
#include <cmath>
#include <iostream>
#include <limits>

#include "bench_util.hpp"
#include "knit/recipes/simulate_scene.hpp"

namespace {

struct Spec {
  knit::Integrator integrator;
  double h;
  std::string text;
  bool implicit_bending = false;
  double contact_solve_tolerance = 0;
};

Spec parse_spec(const std::string& text) {
  const size_t colon = text.find(':');
  if (colon == std::string::npos)
    throw std::invalid_argument("'" + text +
                                "': expected INTEGRATOR[+bending][+cg]:H (e.g. imex:4e-4)");
  std::string name = text.substr(0, colon);
  // strips `suffix` from the end of name, saying whether it was there
  auto strip = [&](const std::string& suffix) {
    const bool has = name.size() > suffix.size() &&
                     name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0;
    if (has) name.resize(name.size() - suffix.size());
    return has;
  };
  const bool cg = strip("+cg");
  const bool bending = strip("+bending");
  return {knit::parse_integrator(name), std::stod(text.substr(colon + 1)), text, bending,
          cg ? 1e-3 : 0.0};
}

struct Outcome {
  bool stable = true;
  long steps = 0;
  double failed_at_s = -1;
  double wall_s = 0;
  knit::State state;
  std::map<std::string, double> stage_seconds;
  double min_d = std::numeric_limits<double>::infinity();  // closest yarn approach, any step
  double deepest_object_overlap = 0;                       // cm, any object, any step
};

// The sample's shape at the end, for runs whose control points cannot be compared one by
// one (a scarf folding onto a floor lands in a different fold at any step): the centre
// of its control points and the extent of their bounding box along x, y and z (cm).
struct Shape {
  Eigen::Vector3d centre, extent;
};

Shape shape_of(const Eigen::VectorXd& q) {
  const auto p = q.reshaped(3, q.size() / 3);
  return {p.rowwise().mean(), p.rowwise().maxCoeff() - p.rowwise().minCoeff()};
}

Outcome run(const knit::Scene& base, const Spec& spec, double duration) {
  knit::Scene scene = base;
  scene.model.params.solver.time_step = spec.h;
  scene.model.params.solver.integrator = spec.integrator;
  scene.model.params.solver.implicit_bending = spec.implicit_bending;
  scene.model.params.solver.contact_solve_tolerance = spec.contact_solve_tolerance;
  auto sim = knit::make_scene_simulator(scene);
  Outcome o;
  o.state = scene.state;
  const double end = o.state.time + duration;
  const auto t0 = std::chrono::steady_clock::now();
  while (o.state.time < end - 1e-9 * spec.h) {
    const double h = std::min(spec.h, end - o.state.time);
    const knit::StepResult r = sim->step(o.state, h);
    if (!r.ok()) {
      o.stable = false;
      o.failed_at_s = o.state.time;
      break;
    }
    ++o.steps;
    const knit::StepData& data = sim->data();
    o.min_d = std::min(o.min_d, data.contact.min_distance_ratio);
    for (const knit::ObjectRecord& obj : data.objects)
      o.deepest_object_overlap = std::max(o.deepest_object_overlap, obj.deepest_penetration);
  }
  o.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  o.stage_seconds = sim->data().stage_seconds;
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  std::string scene_path = KNIT_EXAMPLES "/hanging_knit.json", knit_path;
  std::string runs_text =
      "explicit:2e-4,imex:2e-4,imex:3e-4,imex:4e-4,imex-contact:8e-4,imex-contact:1.6e-3,"
      "imex-contact+bending:3.2e-3";
  double end_mass_floor = -1;
  std::string reference_text = "explicit:8.474576271186441e-05";  // 1/11800 s
  double duration = 1.0;
  int threads = 0;
  CLI::App app{"bench_time_to_solution: wall seconds per simulated second, and the error"};
  app.add_option("--scene", scene_path, "scene file (JSON)");
  app.add_option("--knit", knit_path, "place this relaxed knit (.kstate) in the scene");
  app.add_option("--time", duration, "simulated seconds per run");
  app.add_option("--runs", runs_text,
                 "comma-separated INTEGRATOR:H (explicit, imex or imex-contact; s), "
                 "INTEGRATOR+bending:H for implicit bending too");
  app.add_option("--reference", reference_text, "the reference run, INTEGRATOR:H");
  app.add_option("--threads", threads, "0 = all cores");
  app.add_option("--end-mass-floor", end_mass_floor,
                 "the yarn ends' mass floor (0–1; default: the scene's)");
  CLI11_PARSE(app, argc, argv);
  const auto gc = knit::bench::limit_threads(threads);

  knit::Scene scene = knit_path.empty() ? knit::load_scene(scene_path)
                                        : knit::load_scene_with_knit(scene_path, knit_path);
  if (end_mass_floor >= 0) {
    knit::check_param("end_mass_floor", end_mass_floor);
    scene.model.params.discretisation.end_mass_floor = end_mass_floor;
    knit::apply_end_mass_floor(scene.model, end_mass_floor);
  }
  const double r = scene.model.params.material.radius;
  const Spec ref_spec = parse_spec(reference_text);
  std::vector<Spec> specs{ref_spec};
  for (const std::string& t : knit::bench::split_list(runs_text)) specs.push_back(parse_spec(t));

  nlohmann::json runs = nlohmann::json::array();
  knit::State reference;
  double reference_rate = 0;
  for (size_t k = 0; k < specs.size(); ++k) {
    const Spec& spec = specs[k];
    const Outcome o = run(scene, spec, duration);
    if (k == 0) {
      if (!o.stable)
        throw std::runtime_error("the reference run " + spec.text +
                                 " went unstable at t = " + std::to_string(o.failed_at_s) + " s");
      reference = o.state;
      reference_rate = o.wall_s / duration;
    }
    nlohmann::json j = {{"integrator", knit::integrator_name(spec.integrator)},
                        {"implicit_bending", spec.implicit_bending},
                        {"contact_solve_tolerance", spec.contact_solve_tolerance},
                        {"h", spec.h},
                        {"reference", k == 0},
                        {"stable", o.stable},
                        {"steps", o.steps},
                        {"wall_s", o.wall_s},
                        {"us_per_segment_step",
                         1e6 * o.wall_s / std::max<long>(o.steps, 1) / scene.model.num_seg()},
                        {"stage_seconds", o.stage_seconds}};
    if (o.stable) {
      const double err =
          (o.state.q - reference.q).reshaped(3, reference.q.size() / 3).colwise().norm().maxCoeff();
      j["wall_s_per_sim_s"] = o.wall_s / duration;
      j["speedup_vs_reference"] = reference_rate / (o.wall_s / duration);
      j["max_error_cm"] = err;
      j["max_error_radii"] = err / r;
      const Shape a = shape_of(o.state.q), b = shape_of(reference.q);
      j["centre_cm"] = {a.centre.x(), a.centre.y(), a.centre.z()};
      j["extent_cm"] = {a.extent.x(), a.extent.y(), a.extent.z()};
      j["centre_error_cm"] = (a.centre - b.centre).norm();
      j["extent_error_cm"] = (a.extent - b.extent).cwiseAbs().maxCoeff();
      j["closest_approach_d"] = std::isfinite(o.min_d) ? nlohmann::json(o.min_d) : nullptr;
      // a run whose yarns came within half the contact distance has let them pass (or
      // nearly): its rate is not a result, however stable its steps
      j["contact_held"] = !(o.min_d < 0.5);
      j["deepest_object_overlap_cm"] = o.deepest_object_overlap;
    } else {
      j["failed_at_s"] = o.failed_at_s;
    }
    std::cerr << "time_to_solution: " << spec.text << ": "
              << (o.stable
                      ? std::to_string(o.wall_s / duration) + " wall s per sim s, error " +
                            std::to_string(j["max_error_radii"].get<double>()) + " r, centre " +
                            std::to_string(j["centre_error_cm"].get<double>()) + " cm, extent " +
                            std::to_string(j["extent_error_cm"].get<double>()) + " cm" +
                            (o.min_d < 0.5 ? ", yarns within d = " + std::to_string(o.min_d) +
                                                 ": contact did not hold, not a result"
                                           : "")
                      : "unstable at t = " + std::to_string(o.failed_at_s) + " s")
              << "\n";
    runs.push_back(j);
  }
  nlohmann::json out = {{"benchmark", "time_to_solution"},
                        {"machine", knit::bench::machine_info()},
                        {"threads", knit::bench::active_threads()},
                        {"scene", scene_path},
                        {"knit", knit_path},
                        {"segments", scene.model.num_seg()},
                        {"simulated_s", duration},
                        {"runs", runs}};
  std::cout << out.dump(2) << "\n";
}
