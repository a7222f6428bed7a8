// The Python module `knitsim`: the library's recipes (relax a knit, stretch it, run a
// scene) and its core (Model, State, Simulator, StepData) for Debian's python3 with numpy.
//
// Arrays: State.q and State.v are numpy views of the state's own memory, shape (num_cp, 3)
// (writing into them changes the state); everything else is a fresh array or dict.
// Errors: the library's messages with the options they name ("--rows", "max-time = …")
// named as this module's keyword arguments (rows, max_time; docs/cli.md, "From Python"):
// std::invalid_argument becomes ValueError, InputError (bad scene or file contents)
// ValueError, a missing file (FileNotFound) FileNotFoundError, other std::runtime_error
// RuntimeError; a step that fails raises knitsim.StepError (a RuntimeError) and leaves the
// state as it was.
// Options: every function takes the options of the command it stands for, as keyword
// arguments with the command's defaults (the library's); None: the recipe's default, or
// the resumed state's.
// Long calls (relax, stretch, run, step) release the GIL; Ctrl-C ends a relax, stretch or
// run after the current step as `knitsim relax` does (status "interrupted"), and then
// raises KeyboardInterrupt.
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <csignal>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <regex>
#include <set>
#include <string>

#include "knit/analysis/fabric_shape.hpp"
#include "knit/io/export.hpp"
#include "knit/io/state_file.hpp"
#include "knit/io/states.hpp"
#include "knit/pattern/graph_summary.hpp"
#include "knit/pattern/knitout.hpp"
#include "knit/present/stretch_figures.hpp"
#include "knit/recipes/relax_knit.hpp"
#include "knit/recipes/sheet_stretch.hpp"
#include "knit/recipes/simulate_scene.hpp"
#include "knit/recipes/stretch.hpp"
#include "knit/run/interrupt.hpp"
#include "knit/run/runner.hpp"
#include "knit/scene/json_reader.hpp"
#include "knit/scene/scene.hpp"
#include "knit/solver/simulator.hpp"
#include "knit/util/input_file.hpp"
#include "knit/util/run_dir.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace knit {
namespace {

// ---------------------------------------------------------------- conversions

py::object to_python(const nlohmann::json& j) {
  return py::module_::import("json").attr("loads")(j.dump());
}

nlohmann::json to_json(const py::handle& obj) {
  const std::string text = py::str(py::module_::import("json").attr("dumps")(obj));
  return nlohmann::json::parse(text);
}

py::array_t<double> vec3(const Eigen::Vector3d& v) {
  py::array_t<double> a(3);
  for (int c = 0; c < 3; ++c) a.mutable_at(c) = v[c];
  return a;
}

// a (n, 3) view of a stacked xyz vector whose memory `owner` keeps alive
py::array_t<double> xyz_view(Eigen::VectorXd& x, py::handle owner) {
  const auto n = static_cast<py::ssize_t>(x.size() / 3);
  return py::array_t<double>({n, py::ssize_t{3}},
                             {py::ssize_t{3 * sizeof(double)}, py::ssize_t{sizeof(double)}},
                             x.data(), owner);
}

// a stacked xyz vector from an (n, 3) or flat array of 3n numbers
Eigen::VectorXd xyz_from(const py::array_t<double, py::array::c_style | py::array::forcecast>& a,
                         const char* what) {
  if (!((a.ndim() == 2 && a.shape(1) == 3) || (a.ndim() == 1 && a.shape(0) % 3 == 0)))
    throw std::invalid_argument(std::string(what) +
                                ": expected an (n, 3) array or a flat one of 3n numbers");
  Eigen::VectorXd x(a.size());
  std::copy(a.data(), a.data() + a.size(), x.data());
  return x;
}

void assign_xyz(Eigen::VectorXd& x,
                const py::array_t<double, py::array::c_style | py::array::forcecast>& a,
                const char* what) {
  Eigen::VectorXd y = xyz_from(a, what);
  if (x.size() && y.size() != x.size())
    throw std::invalid_argument(std::string(what) + ": " + std::to_string(y.size() / 3) +
                                " points for a state of " + std::to_string(x.size() / 3));
  x = std::move(y);
}

py::array_t<int> stitch_array(const std::vector<StitchCoord>& stitch) {
  py::array_t<int> a({static_cast<py::ssize_t>(stitch.size()), py::ssize_t{2}});
  auto m = a.mutable_unchecked<2>();
  for (size_t i = 0; i < stitch.size(); ++i) {
    m(i, 0) = stitch[i].row;
    m(i, 1) = stitch[i].col;
  }
  return a;
}

py::dict knit_info(const std::optional<KnitInfo>& k) {
  py::dict d;
  if (!k) return d;
  d["pattern"] = k->pattern;
  d["rows"] = k->rows;
  d["cols"] = k->cols;
  d["in_the_round"] = k->in_the_round;
  d["segments_per_stitch"] = k->segments_per_stitch;
  d["stitch_size_cm"] = k->stitch_size_cm;
  d["shrink"] = k->shrink;
  d["bind_off"] = k->bind_off;
  d["cast_on"] = k->cast_on;
  if (k->relaxation) d["relaxation"] = to_python(to_json(*k->relaxation));
  return d;
}

Params params_over(const Params& base, const py::object& overrides, const char* where) {
  if (overrides.is_none()) return base;
  const nlohmann::json j = to_json(overrides);
  return parse_params(JsonReader(j, where, "params"), base);
}

// ---------------------------------------------------------------- errors

// The keyword argument for the command-line option `flag` (without its "--").
std::string keyword(const std::string& flag) {
  static const std::map<std::string, std::string> renamed = {{"round", "in_the_round"},
                                                             {"ke-threshold", "rest"},
                                                             {"quiet", "progress"},
                                                             {"no-frames", "frames"},
                                                             {"no-render", "render"}};
  const auto it = renamed.find(flag);
  if (it != renamed.end()) return it->second;
  std::string k = flag;
  std::replace(k.begin(), k.end(), '-', '_');
  return k;
}

// The options that take no value: "--bind-off" reads bind_off=True, "no --bind-off"
// bind_off=False.
bool is_switch(const std::string& flag) {
  static const std::set<std::string> switches = {"round",       "bind-off",  "cast-on",
                                                 "fire",        "overwrite", "implicit-bending",
                                                 "hold-damped", "sheet"};
  return switches.count(flag) > 0;
}

// `message` with the options it names as keyword arguments: "--rows" → "rows", "no
// --round" → "in_the_round=False", a leading "max-time: " → "max_time: ".
std::string keyword_message(const std::string& message) {
  static const std::regex flag(R"((^|[\s(\[`"'])(no )?--([a-z][a-z0-9]*(?:-[a-z0-9]+)*))");
  static const std::regex lead(R"(^([a-z]+(?:-[a-z]+)+)(: | = ))");
  static const std::set<std::string> leading = {"max-time",
                                                "ke-threshold",
                                                "contact-reuse-widen",
                                                "contact-reuse-widen-residual",
                                                "check-every",
                                                "checkpoint-every",
                                                "time-step",
                                                "max-step-halvings",
                                                "end-mass-floor",
                                                "contact-points",
                                                "contact-solve-tolerance",
                                                "contact-reuse",
                                                "segments-per-stitch",
                                                "stitch-size",
                                                "hold-time",
                                                "max-force",
                                                "clamp-stitches",
                                                "output-every",
                                                "k-global",
                                                "alpha-small",
                                                "alpha-large",
                                                "yarn-friction",
                                                "node-spacing"};
  std::string out;
  auto begin = message.cbegin();
  for (std::sregex_iterator it(message.begin(), message.end(), flag), end; it != end; ++it) {
    const std::smatch& m = *it;
    out.append(begin, m[0].first);
    const std::string name = m[3], kw = keyword(name);
    const bool no = m[2].matched;
    out += m[1].str();
    if (is_switch(name))
      out += kw + (no ? "=False" : "=True");
    else
      out += (no ? "no " : "") + kw;
    begin = m[0].second;
  }
  out.append(begin, message.cend());
  std::smatch m;
  if (std::regex_search(out, m, lead) && leading.count(m[1]))
    out = keyword(m[1]) + m[2].str() + m.suffix().str();
  return out;
}

// A path argument that names nothing: FileNotFoundError naming the keyword, before the
// library is asked.
void require_path(const std::string& path, const char* kw) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    throw FileNotFound(std::string(kw) + ": " + path + ": no such file or directory");
}

// The model's parameters given as keywords — any name of the parameter table
// (src/knit/model/params.def, docs/parameters.md, knitsim.parameters()), as `params` takes
// them — laid over the `params` dict (a keyword wins): one dict for params_over. A keyword
// that is neither an argument nor a parameter is a TypeError naming it; with `only_group`,
// one of another group is refused. `given` receives the names given either way.
py::object params_and_keywords(const py::object& params, const py::kwargs& kw, const char* where,
                               std::set<std::string>* given = nullptr,
                               const char* only_group = nullptr) {
  py::dict merged;
  if (py::isinstance<py::dict>(params))
    merged = params.cast<py::dict>().attr("copy")();
  else if (!params.is_none())
    return params;  // (params_over names what is wrong with it)
  for (auto item : kw) {
    const std::string key = item.first.cast<std::string>();
    const auto& table = param_table();
    if (std::none_of(table.begin(), table.end(), [&](const ParamDecl& d) { return key == d.name; }))
      throw py::type_error(std::string(where) + "() got an unexpected keyword argument '" + key +
                           "': neither one of its arguments nor a parameter of the model "
                           "(docs/parameters.md)");
    if (only_group && param_decl(key).group != std::string(only_group))
      throw std::invalid_argument(std::string(where) + ": " + key + " is a " +
                                  param_decl(key).group + " parameter; only the " + only_group +
                                  "'s change for a run (set the others in the scene)");
    merged[py::str(key)] = item.second;
  }
  if (given)
    for (auto item : merged) given->insert(item.first.cast<std::string>());
  return merged.empty() ? params : py::object(merged);
}

// --threads for the length of a call (0: as set_threads left it)
std::unique_ptr<tbb::global_control> thread_limit(int threads) {
  if (threads < 0) throw std::invalid_argument("threads: must be >= 0 (0: all cores)");
  if (threads == 0) return nullptr;
  return std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                               static_cast<size_t>(threads));
}

// --export FORMAT of relax and simulate: checked before the run, written after it into `out`
// (usd: every state as frames.usda; else the final state as final.EXT)
void check_export(const std::string& format, const std::string& out) {
  if (format.empty()) return;
  try {
    export_extension(format);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("export: ") + e.what());
  }
  if (out.empty()) throw std::invalid_argument("export: exports the run in `out`: give one");
}

void export_outputs(const std::string& format, const std::string& out,
                    const std::vector<std::shared_ptr<const SceneObject>>& objects = {}) {
  namespace fs = std::filesystem;
  if (format.empty()) return;
  const fs::path dir(out);
  if (format == "usd") {
    std::vector<StateFile> frames;
    std::vector<double> times;
    const std::vector<std::string> paths =
        fs::exists(dir / "frames") ? list_state_files((dir / "frames").string())
                                   : std::vector<std::string>{(dir / "final.kstate").string()};
    for (const std::string& path : paths) {
      frames.push_back(read_state_file(path));
      times.push_back(frames.back().state.time);
    }
    export_usd(frames, times, (dir / "frames.usda").string(), objects);
    return;
  }
  ExportOptions options;
  options.objects = objects;
  export_state(read_state_file((dir / "final.kstate").string()), format,
               (dir / ("final" + export_extension(format))).string(), options);
}

std::string num(double x) {
  return short_number(x);
}

// ---------------------------------------------------------------- step data

py::dict contact_dict(const ContactRecord& c) {
  const auto n = static_cast<py::ssize_t>(c.pairs.size());
  py::array_t<int> seg_i(n), seg_j(n);
  py::array_t<double> d(n), force(n), t_i(n), t_j(n), normal({n, py::ssize_t{3}});
  auto nm = normal.mutable_unchecked<2>();
  for (py::ssize_t k = 0; k < n; ++k) {
    const ContactPairRecord& p = c.pairs[k];
    seg_i.mutable_at(k) = p.seg_i;
    seg_j.mutable_at(k) = p.seg_j;
    d.mutable_at(k) = p.d;
    force.mutable_at(k) = p.normal_force;
    t_i.mutable_at(k) = p.t_i;
    t_j.mutable_at(k) = p.t_j;
    for (int a = 0; a < 3; ++a) nm(k, a) = p.normal[a];
  }
  return py::dict("present"_a = c.present, "candidate_segment_pairs"_a = c.candidate_segment_pairs,
                  "point_pairs_tested"_a = c.point_pairs_tested,
                  "point_pairs_in_contact"_a = c.point_pairs_in_contact,
                  "min_distance_ratio"_a = c.min_distance_ratio, "seg_i"_a = seg_i,
                  "seg_j"_a = seg_j, "d"_a = d, "normal"_a = normal, "normal_force"_a = force,
                  "t_i"_a = t_i, "t_j"_a = t_j);
}

// StepData as plain Python values: numbers, dicts and numpy arrays
py::dict step_data_dict(const StepData& s) {
  py::dict energies, term_forces, stages;
  for (const TermRecord& t : s.terms) {
    energies[py::str(t.name)] = t.energy;
    term_forces[py::str(t.name)] = vec3(t.net_force);
  }
  for (const auto& [name, seconds] : s.stage_seconds) stages[py::str(name)] = seconds;
  py::list constraints, objects;
  for (const ConstraintRecord& c : s.constraints) {
    py::array_t<double> mult(c.multipliers.size());
    std::copy(c.multipliers.data(), c.multipliers.data() + c.multipliers.size(),
              mult.mutable_data());
    constraints.append(py::dict("name"_a = c.name, "kind"_a = c.kind, "rows"_a = c.rows,
                                "force"_a = vec3(c.force), "torque"_a = vec3(c.torque),
                                "about"_a = vec3(c.about), "max_violation"_a = c.max_violation,
                                "multipliers"_a = mult));
  }
  for (const ObjectRecord& o : s.objects)
    objects.append(py::dict("name"_a = o.name, "points_in_contact"_a = o.points_in_contact,
                            "deepest_penetration"_a = o.deepest_penetration,
                            "force"_a = vec3(o.force)));
  return py::dict(
      "steps"_a = s.steps, "time"_a = s.time, "kinetic_energy"_a = s.kinetic_energy,
      "potential_energy"_a = s.potential_energy, "energies"_a = energies,
      "term_forces"_a = term_forces, "contact"_a = contact_dict(s.contact), "objects"_a = objects,
      "max_violation"_a = s.max_violation,
      "projection"_a =
          py::dict("converged"_a = s.projection.converged, "iterations"_a = s.projection.iterations,
                   "residual"_a = s.projection.residual),
      "constraints"_a = constraints,
      "friction"_a = py::dict("present"_a = s.friction.present, "pairs"_a = s.friction.pairs,
                              "stuck"_a = s.friction.stuck, "work"_a = s.friction.work,
                              "force"_a = s.friction.force, "passes"_a = s.friction.passes),
      "stage_seconds"_a = stages, "warnings"_a = s.warnings,
      "force_residual"_a = std::isfinite(s.force_residual)
                               ? py::object(py::float_(s.force_residual))
                               : py::object(py::none()),
      "force_residual_peak"_a =
          std::isfinite(s.force_residual)
              ? py::object(py::dict("control_point"_a = s.force_residual_peak.control_point,
                                    "acceleration"_a = s.force_residual_peak.acceleration,
                                    "top_percent_share"_a = s.force_residual_peak.top_share))
              : py::object(py::none()));
}

// ---------------------------------------------------------------- runs

// Runs `body` without the GIL, with Ctrl-C ending the run after the current step; raises
// KeyboardInterrupt afterwards when that happened.
template <class F>
auto run_interruptible(F&& body) {
  clear_interrupt();
  std::optional<decltype(body())> result;
  {
    InterruptHandler handler;
    py::gil_scoped_release release;
    result.emplace(body());
  }
  const int signal = interrupt_signal();
  clear_interrupt();
  if (signal == SIGINT) {
    PyErr_SetNone(PyExc_KeyboardInterrupt);
    throw py::error_already_set();
  }
  return std::move(*result);
}

py::dict report_dict(const RunReport& r) {
  return py::dict("status"_a = status_word(r.status), "message"_a = r.message, "steps"_a = r.steps,
                  "summary"_a = to_python(r.summary));
}

// the knit a relaxation produced: model, last state and report
struct Knit {
  RelaxResult result;
};

// a step that failed (Python: knitsim.StepError)
struct StepFailed : std::runtime_error {
  using std::runtime_error::runtime_error;
};

std::unique_ptr<tbb::global_control> g_threads;

}  // namespace
}  // namespace knit

PYBIND11_MODULE(knitsim, m) {
  using namespace knit;
  m.doc() =
      "knitsim: yarn-level simulation of knitted cloth (units cm, g, s).\n\n"
      "  k = knitsim.relax('stockinette', rows=12, cols=12)   # generate and relax\n"
      "  k.shape['stitch_width_cm'], k.shape['row_height_cm'] # its gauge\n"
      "  k.state.q                                            # control points, (n, 3)\n";
  m.attr("__version__") = KNIT_VERSION;

  py::register_exception<StepFailed>(m, "StepError", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const FileNotFound& e) {
      PyErr_SetString(PyExc_FileNotFoundError, keyword_message(e.what()).c_str());
    } catch (const InputError& e) {
      PyErr_SetString(PyExc_ValueError, keyword_message(e.what()).c_str());
    } catch (const std::invalid_argument& e) {
      PyErr_SetString(PyExc_ValueError, keyword_message(e.what()).c_str());
    }
  });

  m.def(
      "set_threads",
      [](int threads) {
        if (threads < 0) throw std::invalid_argument("threads: must be >= 0 (0: all cores)");
        g_threads.reset();
        if (threads > 0)
          g_threads = std::make_unique<tbb::global_control>(
              tbb::global_control::max_allowed_parallelism, static_cast<size_t>(threads));
      },
      "threads"_a, "Use at most this many threads (0: all cores).");

  m.def(
      "knit_graph",
      [](const std::string& path, bool loops) {
        require_path(path, "path");
        // (ordered JSON, whose keys keep their order through json.loads)
        return py::module_::import("json").attr("loads")(knit_graph_json(path, loops).dump());
      },
      "path"_a, "loops"_a = false,
      "The knit graph of a knitout program (.k, .knitout: run on the machine model) or a "
      "hand-knitting chart (.chart), as `knitsim graph` prints it: a dict of its loops by kind, "
      "face and bed, yarns, passes, free loops, crossings, stitch settings, the checks' "
      "problems, the interpreter's notes and, for a program, `sheet` (what relax lays of it, or "
      "why not); with `loops`, `loop_list`: every loop's id, yarn, needle, pass, course, kind, "
      "face, direction, line, end and parents (bottom of the needle's stack first).");

  // ------------------------------------------------------------- State
  py::class_<State>(m, "State", "Control-point positions q and velocities v (cm, cm/s), time (s).")
      .def(py::init([](const py::array_t<double, py::array::c_style | py::array::forcecast>& q,
                       const py::object& v, double time) {
             State s;
             s.q = xyz_from(q, "q");
             s.v = Eigen::VectorXd::Zero(s.q.size());
             if (!v.is_none())
               assign_xyz(s.v,
                          v.cast<py::array_t<double, py::array::c_style | py::array::forcecast>>(),
                          "v");
             s.time = time;
             return s;
           }),
           "q"_a, "v"_a = py::none(), "time"_a = 0.0)
      .def_property(
          "q", [](py::object self) { return xyz_view(self.cast<State&>().q, self); },
          [](State& s, const py::array_t<double, py::array::c_style | py::array::forcecast>& a) {
            assign_xyz(s.q, a, "q");
          },
          "Control points, (num_cp, 3) view (cm).")
      .def_property(
          "v", [](py::object self) { return xyz_view(self.cast<State&>().v, self); },
          [](State& s, const py::array_t<double, py::array::c_style | py::array::forcecast>& a) {
            assign_xyz(s.v, a, "v");
          },
          "Velocities, (num_cp, 3) view (cm/s).")
      .def_readwrite("time", &State::time, "s")
      .def_property_readonly("num_cp", [](const State& s) { return s.q.size() / 3; })
      .def("copy", [](const State& s) { return State(s); })
      .def("__repr__", [](const State& s) {
        return "<knitsim.State " + std::to_string(s.q.size() / 3) +
               " control points, t = " + std::to_string(s.time) + " s>";
      });

  // ------------------------------------------------------------- Model
  py::class_<Model>(m, "Model", "The immutable model: yarns, rest lengths, constraints, params.")
      .def_property_readonly("num_cp", &Model::num_cp)
      .def_property_readonly("num_seg", &Model::num_seg)
      .def_property_readonly("num_yarns", [](const Model& mo) { return mo.yarns.size(); })
      .def_property_readonly(
          "yarn_cp_counts",
          [](const Model& mo) {
            std::vector<int> n;
            for (const YarnInfo& y : mo.yarns) n.push_back(y.num_cp());
            return n;
          },
          "Control points per yarn.")
      .def_property_readonly(
          "radius", [](const Model& mo) { return mo.params.material.radius; },
          "Yarn radius r (cm).")
      .def_property_readonly(
          "time_step", [](const Model& mo) { return mo.params.solver.time_step; }, "h (s).")
      .def_property_readonly(
          "integrator",
          [](const Model& mo) { return std::string(integrator_name(mo.params.solver.integrator)); },
          "\"explicit\", \"imex\" or \"imex-contact\" (params {\"integrator\": ...}).")
      .def_property_readonly(
          "stitch", [](const Model& mo) { return stitch_array(mo.stitch); },
          "(num_seg, 2) int array: each segment's stitch (row, column); -1 where none.")
      .def_property_readonly(
          "rest_length",
          [](const Model& mo) {
            return py::array_t<double>(static_cast<py::ssize_t>(mo.rest_length.size()),
                                       mo.rest_length.data());
          },
          "Rest length of each segment (cm).")
      .def_property_readonly(
          "mass",
          [](const Model& mo) { return py::array_t<double>(mo.mass.size(), mo.mass.data()); },
          "Lumped mass of each control point (g).")
      .def_property_readonly(
          "clamps",
          [](const Model& mo) {
            std::vector<std::string> n;
            for (const Clamp& c : mo.clamps) n.push_back(c.name);
            return n;
          },
          "Names of the clamps.")
      .def_property_readonly(
          "knit", [](const Model& mo) { return knit_info(mo.knit); },
          "Where a generated knit came from (empty for other yarns).")
      .def_property_readonly("total_length", &Model::total_length, "Total rest length (cm).")
      .def("__repr__", [](const Model& mo) {
        return "<knitsim.Model " + std::to_string(mo.yarns.size()) + " yarns, " +
               std::to_string(mo.num_seg()) + " segments>";
      });

  m.def(
      "measure_fabric",
      [](const Model& mo, const State& s) { return to_python(to_json(measure_fabric(mo, s.q))); },
      "model"_a, "state"_a,
      "The fabric's shape (a knit's model): width, height, thickness, gauge (stitch width, row "
      "height), edge curl … as a dict (cm).");

  // ------------------------------------------------------------- Simulator
  py::class_<Simulator>(m, "Simulator",
                        "Steps a state: forces → explicit midpoint → projection → filters.")
      .def(py::init([](const Model& mo) { return std::make_unique<Simulator>(mo); }), "model"_a,
           "A simulator with the model's default terms (no velocity filters).")
      .def_property_readonly("model", &Simulator::model,
                             py::return_value_policy::reference_internal)
      .def(
          "step",
          [](Simulator& sim, State& s, std::optional<double> h, int steps) {
            if (steps < 1) throw std::invalid_argument("steps: must be >= 1");
            StepResult r;
            {
              py::gil_scoped_release release;
              for (int k = 0; k < steps && r.ok(); ++k) r = h ? sim.step(s, *h) : sim.step(s);
            }
            if (!r.ok()) throw StepFailed(r.message);
          },
          "state"_a, "h"_a = py::none(), "steps"_a = 1,
          "Advances `state` by `steps` steps of h (default: the model's). Raises StepError "
          "when a step fails (the state stays the last good one).")
      .def(
          "run",
          [](Simulator& sim, State& s, double duration, int output_every, const std::string& out,
             bool progress) {
            RunOptions o;
            o.duration = duration;
            o.output_every = output_every;
            o.out_dir = out;
            o.progress = progress;
            o.write_frames = !out.empty();
            const RunReport r = run_interruptible([&] { return run_simulation(sim, s, o); });
            return report_dict(r);
          },
          "state"_a, "duration"_a, "output_every"_a = 100, "out"_a = "", "progress"_a = false,
          "Runs for `duration` s (writing the run into `out`, a new or empty folder, when "
          "given); returns the report "
          "(status, message, steps, summary).")
      .def(
          "forward", [](Simulator& sim, const State& s) { sim.forward(s); }, "state"_a,
          "Evaluates the forces at `state` and records them in `data`.")
      .def_property_readonly(
          "data", [](const Simulator& sim) { return step_data_dict(sim.data()); },
          "What the last forward and step recorded (energies, contact set, constraint forces, "
          "…) as a dict with numpy arrays.")
      .def("kinetic_energy", &Simulator::kinetic_energy, "state"_a, "erg")
      .def("potential_energy", &Simulator::potential_energy, "state"_a, "erg")
      .def(
          "force_residual",
          [](Simulator& sim, const State& s) {
            py::gil_scoped_release release;
            return sim.force_residual(s);
          },
          "state"_a,
          "The net static force per unit mass that the constraints do not hold (cm/s²; 0 at a "
          "rest); `data` then says where it sits (force_residual_peak: the global control "
          "point furthest from rest, its acceleration, the share of the top 1 %).")
      .def(
          "linear_momentum",
          [](const Simulator& sim, const State& s) { return vec3(sim.linear_momentum(s)); },
          "state"_a, "g cm/s")
      .def("max_violation", &Simulator::max_violation, "state"_a,
           "max |C| over the constraints (cm)");

  // ------------------------------------------------------------- knits
  py::class_<Knit>(m, "Knit", "A relaxed knit: its model, last state and the run's report.")
      .def_property_readonly(
          "model", [](Knit& k) -> const Model& { return k.result.model; },
          py::return_value_policy::reference_internal)
      .def_property_readonly(
          "state", [](Knit& k) -> State& { return k.result.state; },
          py::return_value_policy::reference_internal)
      .def_property_readonly("status",
                             [](const Knit& k) { return status_word(k.result.report.status); })
      .def_property_readonly("message", [](const Knit& k) { return k.result.report.message; })
      .def_property_readonly("steps", [](const Knit& k) { return k.result.report.steps; })
      .def_property_readonly("summary",
                             [](const Knit& k) { return to_python(k.result.report.summary); })
      .def_property_readonly(
          "shape",
          [](const Knit& k) {
            return to_python(to_json(measure_fabric(k.result.model, k.result.state.q)));
          },
          "The relaxed fabric's shape and gauge (see measure_fabric).")
      .def(
          "save",
          [](const Knit& k, const std::string& path) {
            write_state_file(path, make_state_file(k.result.model, k.result.state));
          },
          "path"_a, "Writes the knit as a .kstate (what `knitsim relax` writes).")
      .def("__repr__", [](const Knit& k) {
        return "<knitsim.Knit " + std::to_string(k.result.model.num_seg()) + " segments, " +
               status_word(k.result.report.status) +
               ", t = " + std::to_string(k.result.state.time) + " s>";
      });

  // the defaults the docstrings name: the recipes' own
  const Params relax_defaults = relax_knit_params(), yarns_defaults = relax_yarns_params(),
               stretch_defaults = stretch_params();
  const RelaxKnitOptions relax_options;
  const RelaxOptions relax_run;
  static const std::string solver_doc =
      "Every parameter of the model (docs/parameters.md: its name, unit and range) is also a "
      "keyword, as in `params` (a dict of them, docs/scene-format.md; a parameter given both "
      "ways is refused): the solver's `time_step` (s), `integrator` (\"explicit\", \"imex\" "
      "or \"imex-contact\"), `implicit_bending`, `contact_solve_tolerance` (fraction), "
      "`contact_reuse` (yarn radii), `max_step_halvings`, `refuse_crossings`, the damping's "
      "`k_global`, `alpha_small`, `alpha_large`, `yarn_friction`, `end_mass_floor`, "
      "`contact_points`, …; `threads` (0: as set_threads left it).";
  static const std::string relax_doc =
      "Generates `pattern` (stockinette, garter, rib2x2, seed, … a chart file or a knitout "
      "program) at rows × cols (default " +
      std::to_string(relax_options.knit.rows) + " × " + std::to_string(relax_options.knit.cols) +
      ", or the program's size) and relaxes it until it rests (kinetic energy per length below "
      "`rest` erg/cm, default " +
      num(relax_run.ke_per_length) +
      ", or with `residual` > 0 the force residual below `residual` cm/s²) or `max_time` s of "
      "simulated time (`knitsim relax`; docs/cli.md). `fire`: relax by minimisation (FIRE; "
      "rest by the force residual, " +
      num(RELAX_FIRE_RESIDUAL) +
      " cm/s² unless `residual` says). `bind_off`: tie the last row's loops to the row below "
      "(a sewn bind-off); `cast_on`: tie the second row's loops to the first (a cast-on). "
      "`stitch_size` (cm, 0: the generator's), `shrink` (default " +
      num(relax_options.shrink) + "), `segments_per_stitch` (default " +
      std::to_string(relax_options.knit.segments_per_stitch) +
      "). Damping: `k_global` (g/s, default " + num(relax_defaults.material.k_global) +
      "), `alpha_small`, `alpha_large` (the fraction of the non-rigid velocity removed per "
      "1/11800 s, default " +
      num(relax_defaults.material.alpha_small) + " and " +
      num(relax_defaults.material.alpha_large) + "). " + solver_doc + " Defaults: time step " +
      num(relax_defaults.solver.time_step) + " s, integrator " +
      integrator_name(relax_defaults.solver.integrator) + ", " +
      std::to_string(relax_defaults.discretisation.contact_points) +
      " `contact_points` per segment, `end_mass_floor` " +
      num(relax_defaults.discretisation.end_mass_floor) +
      ". `check_every` steps between rest checks and states (default " +
      std::to_string(relax_run.check_every) +
      "). `resume`: go on from a knitsim.State of the same knit, or from a .kstate path, whose "
      "knit (size, flat or round, bind-off, cast-on, stitch size, shrink) is then the default "
      "and is checked, and whose relaxation (fire, the solver's parameters, damping, rest "
      "test, widening; the file's knit['relaxation']) goes on as it went unless these "
      "arguments or `params` say otherwise. `contact_reuse_widen` (with contact_reuse and the "
      "imex-contact integrator): widen the reuse distance up to this factor (default 1: none) "
      "while the force residual is above `contact_reuse_widen_residual` cm/s² (default " +
      num(relax_run.contact_reuse_widen_residual) +
      "). With `out`, writes the run as `knitsim relax --out` does (`frames`: its states along "
      "the way; without them a checkpoint every `checkpoint_every` wall seconds, default " +
      num(relax_run.checkpoint_every_s) +
      "; `export`: also export the result there, as `knitsim relax --export` does). "
      "`check_crossings`: check every step for yarns that passed through each other (the "
      "summary's `crossings`, as --check-crossings). Returns a Knit.";
  m.def(
      "sweep",
      [](py::args args, py::kwargs kwargs) {
        return py::module_::import("knitsim_sweep").attr("sweep")(*args, **kwargs);
      },
      "sweep(spec, out, scheduler=None, workers=None, threads=1, progress=False) -> "
      "pandas.DataFrame\n\nRuns a sweep spec's jobs (a JSON path or a dict: relax, stretch "
      "and simulate jobs over a grid or a list of arguments) on a Dask cluster into `out`, "
      "each job its own run directory, and returns their table (also OUT/results.csv); a "
      "restarted sweep runs only what is not done. `scheduler`: a running scheduler's address "
      "(default: a local cluster of `workers` processes, all cores). The module knitsim_sweep "
      "(python3-distributed, python3-pandas, python3-tqdm); docs/sweeps.md.");

  m.def(
      "parameters",
      [] {
        py::list out;
        const Params defaults;
        for (const ParamDecl& d : param_table()) {
          py::dict p("name"_a = d.name, "group"_a = d.group, "unit"_a = d.unit, "doc"_a = d.doc,
                     "default"_a = to_python(param_json(d, defaults)));
          if (d.type == ParamType::REAL || d.type == ParamType::INTEGER) {
            p["min"] = d.min;
            p["max"] = d.max;
          }
          if (d.type == ParamType::CHOICE) p["choices"] = d.choices();
          out.append(p);
        }
        return out;
      },
      "The model's parameters (src/knit/model/params.def; docs/parameters.md), each a dict: "
      "name, group (material, discretisation or solver), unit, doc, default, and the working "
      "range min and max (numbers) or the choices. Each is a keyword of relax(), "
      "relax_yarns() and stretch() (Scene.run(): the solver's), and a key of their `params`.");

  m.def(
      "relax",
      [](std::string pattern, std::optional<int> rows, std::optional<int> cols,
         std::optional<bool> in_the_round, double max_time, std::optional<double> rest,
         std::optional<double> stitch_size, std::optional<double> shrink,
         std::optional<int> segments_per_stitch, const py::object& params, const std::string& out,
         bool overwrite, bool progress, const py::object& resume, std::optional<bool> fire,
         std::optional<double> residual, std::optional<bool> bind_off, std::optional<bool> cast_on,
         std::optional<double> contact_reuse_widen,
         std::optional<double> contact_reuse_widen_residual, std::optional<int> check_every,
         std::optional<double> checkpoint_every, bool frames, bool check_crossings, int threads,
         const std::string& export_format, const py::kwargs& kw) {
        check_export(export_format, out);
        RelaxKnitOptions o;
        // resume: a State, or a .kstate path whose knit block gives the defaults (as
        // `knitsim relax --resume FILE`): the knit, and how it was being relaxed
        std::optional<StateFile> resume_file;
        if (py::isinstance<py::str>(resume)) {
          require_path(resume.cast<std::string>(), "resume");
          resume_file = read_state_file(resume.cast<std::string>());
          if (const auto& info = resume_file->knit) {
            if (info->relaxation) apply_relax_settings(*info->relaxation, o);
            if (!rows) rows = info->rows;
            if (!cols) cols = info->cols;
            if (!in_the_round) in_the_round = info->in_the_round;
            if (!bind_off) bind_off = info->bind_off;
            if (!cast_on) cast_on = info->cast_on;
            if (!segments_per_stitch) segments_per_stitch = info->segments_per_stitch;
            if (!stitch_size) stitch_size = info->stitch_size_cm;
            if (!shrink) shrink = info->shrink;
            if (pattern.empty()) pattern = info->pattern;
          }
        } else if (!resume.is_none() && !py::isinstance<State>(resume)) {
          throw py::type_error("relax: resume is a knitsim.State or a .kstate path");
        }
        if (pattern.empty())
          throw std::invalid_argument(
              "relax: give a pattern (or resume from a .kstate that names its own)");
        if (is_knitout_path(pattern)) {
          // a knitting-machine program knits what it says: its size is the default
          require_path(pattern, "pattern");
          const KnitoutPiece piece = load_knitout(pattern);
          o.knit.rows = piece.rows();
          o.knit.cols = piece.cols();
          o.knit.in_the_round = piece.in_the_round;
        }
        if (rows) o.knit.rows = *rows;
        if (cols) o.knit.cols = *cols;
        if (in_the_round) o.knit.in_the_round = *in_the_round;
        if (stitch_size) o.knit.stitch_size_cm = *stitch_size;
        if (segments_per_stitch) o.knit.segments_per_stitch = *segments_per_stitch;
        o.knit.bind_off = bind_off.value_or(false);
        o.knit.cast_on = cast_on.value_or(false);
        if (shrink) o.shrink = *shrink;
        std::set<std::string> given;
        o.params = params_over(o.params, params_and_keywords(params, kw, "relax", &given), "relax");
        if (resume_file && resume_file->knit && resume_file->knit->relaxation) {
          // the file's contact reuse goes with its integrator when another is asked for,
          // and its widening with the reuse (as `knitsim relax --resume`)
          if (given.count("integrator") && !given.count("contact_reuse") &&
              o.params.solver.integrator != Integrator::IMEX_CONTACT)
            o.params.solver.contact_reuse = 0;
          if (o.params.solver.contact_reuse == 0 && !contact_reuse_widen)
            o.run.contact_reuse_widen = 1;
        }
        o.run.max_time = max_time;
        if (rest) o.run.ke_per_length = *rest;
        if (residual) o.run.force_residual = *residual;
        if (contact_reuse_widen) o.run.contact_reuse_widen = *contact_reuse_widen;
        if (contact_reuse_widen_residual)
          o.run.contact_reuse_widen_residual = *contact_reuse_widen_residual;
        if (check_every) o.run.check_every = *check_every;
        if (checkpoint_every) o.run.checkpoint_every_s = *checkpoint_every;
        if (fire) o.fire = *fire;
        if (o.fire)
          for (const char* damping : {"k_global", "alpha_small", "alpha_large"})
            if (given.count(damping))
              throw std::invalid_argument(std::string(damping) +
                                          ": a FIRE relaxation (fire=True) has no damping to set");
        o.run.out_dir = out;
        o.run.overwrite = overwrite;
        o.run.progress = progress;
        o.run.write_frames = frames;
        o.run.check_crossings = check_crossings;
        State resumed;
        if (resume_file) {
          resumed = read_resumed_knit_state(resume.cast<std::string>(), pattern, o.knit);
          o.resume = &resumed;
        } else if (!resume.is_none()) {
          o.resume = resume.cast<const State*>();
        }
        const auto limit = thread_limit(threads);
        auto k = std::make_unique<Knit>();
        k->result = run_interruptible([&] { return relax_knit(pattern, o); });
        export_outputs(export_format, out);
        return k;
      },
      "pattern"_a = "", "rows"_a = py::none(), "cols"_a = py::none(), "in_the_round"_a = py::none(),
      "max_time"_a = relax_run.max_time, "rest"_a = py::none(), "stitch_size"_a = py::none(),
      "shrink"_a = py::none(), "segments_per_stitch"_a = py::none(), "params"_a = py::none(),
      "out"_a = "", "overwrite"_a = false, "progress"_a = false, "resume"_a = py::none(),
      "fire"_a = py::none(), "residual"_a = py::none(), "bind_off"_a = py::none(),
      "cast_on"_a = py::none(), "contact_reuse_widen"_a = py::none(),
      "contact_reuse_widen_residual"_a = py::none(), "check_every"_a = py::none(),
      "checkpoint_every"_a = py::none(), "frames"_a = true, "check_crossings"_a = false,
      "threads"_a = 0, "export"_a = "", relax_doc.c_str());

  static const std::string relax_yarns_doc =
      "Relaxes the yarns of a .yarns, .bcc or .obj file (`knitsim relax --from PATH`): no "
      "stitch coordinates, so no non-rigid damping and no shape measures. `scale` multiplies "
      "the file's coordinates (default: its yarn radius becomes " +
      num(ImportOptions{}.radius) + " cm); `shrink` (default " + num(RELAX_SHRINK) +
      "), `k_global` (g/s, default " + num(yarns_defaults.material.k_global) +
      "), rest, residual, max_time, check_every and the output arguments as relax(). " +
      solver_doc + " Defaults: time step " + num(yarns_defaults.solver.time_step) +
      " s (imported swatches start tightly packed), integrator " +
      integrator_name(yarns_defaults.solver.integrator) + ". Returns a Knit.";
  m.def(
      "relax_yarns",
      [](const std::string& path, std::optional<double> scale, std::optional<double> shrink,
         double max_time, std::optional<double> rest, std::optional<double> residual,
         std::optional<int> check_every, const py::object& params, const std::string& out,
         bool overwrite, bool progress, bool frames, std::optional<double> checkpoint_every,
         bool check_crossings, int threads, const std::string& export_format,
         const py::kwargs& kw) {
        require_path(path, "path");
        check_export(export_format, out);
        RelaxYarnsOptions o;
        if (scale) o.import.scale = *scale;
        if (shrink) o.shrink = *shrink;
        o.params =
            params_over(o.params, params_and_keywords(params, kw, "relax_yarns"), "relax_yarns");
        o.run.max_time = max_time;
        if (rest) o.run.ke_per_length = *rest;
        if (residual) o.run.force_residual = *residual;
        if (check_every) o.run.check_every = *check_every;
        if (checkpoint_every) o.run.checkpoint_every_s = *checkpoint_every;
        o.run.out_dir = out;
        o.run.overwrite = overwrite;
        o.run.progress = progress;
        o.run.write_frames = frames;
        o.run.check_crossings = check_crossings;
        const auto limit = thread_limit(threads);
        auto k = std::make_unique<Knit>();
        k->result = run_interruptible([&] { return relax_yarns(path, o); });
        export_outputs(export_format, out);
        return k;
      },
      "path"_a, "scale"_a = py::none(), "shrink"_a = py::none(), "max_time"_a = relax_run.max_time,
      "rest"_a = py::none(), "residual"_a = py::none(), "check_every"_a = py::none(),
      "params"_a = py::none(), "out"_a = "", "overwrite"_a = false, "progress"_a = false,
      "frames"_a = true, "checkpoint_every"_a = py::none(), "check_crossings"_a = false,
      "threads"_a = 0, "export"_a = "", relax_yarns_doc.c_str());

  // ------------------------------------------------------------- files
  py::class_<StateFile>(m, "StateFile", "A .kstate file's contents.")
      .def_property_readonly(
          "state", [](StateFile& f) -> State& { return f.state; },
          py::return_value_policy::reference_internal)
      .def_readonly("yarn_cp_counts", &StateFile::yarn_cp_counts)
      .def_readonly("yarn_radius", &StateFile::yarn_radius)
      .def_property_readonly("stitch", [](const StateFile& f) { return stitch_array(f.stitch); })
      .def_property_readonly("knit", [](const StateFile& f) { return knit_info(f.knit); })
      .def_property_readonly("num_cp", &StateFile::num_cp)
      .def_property_readonly("num_seg", &StateFile::num_seg);
  m.def(
      "read_state",
      [](const std::string& path) {
        require_path(path, "path");
        return read_state_file(path);
      },
      "path"_a,
      "Reads a .kstate (positions, velocities, yarn layout, stitches, the knit's rest "
      "lengths and glues).");
  m.def(
      "write_state",
      [](const std::string& path, const Model& mo, const State& s) {
        write_state_file(path, make_state_file(mo, s));
      },
      "path"_a, "model"_a, "state"_a, "Writes `state` of `model` as a .kstate, atomically.");

  // ------------------------------------------------------------- scenes
  py::class_<Scene>(m, "Scene", "A scene: model, initial state, duration and output interval.")
      .def_property_readonly(
          "model", [](Scene& s) -> const Model& { return s.model; },
          py::return_value_policy::reference_internal)
      .def_property_readonly(
          "state", [](Scene& s) -> State& { return s.state; },
          py::return_value_policy::reference_internal)
      .def_readwrite("duration", &Scene::duration, "s")
      .def_readwrite("output_every", &Scene::output_every)
      .def(
          "simulator", [](const Scene& s) { return make_scene_simulator(s); },
          "The scene's simulator (its terms and velocity filters), ready to step `state`.")
      .def(
          "run",
          [](Scene& s, const std::string& out, bool overwrite, bool progress,
             const py::object& resume, std::optional<double> duration,
             std::optional<int> output_every, bool check_crossings, int threads,
             const std::string& export_format, const py::kwargs& kw) {
            check_export(export_format, out);
            // the options override the scene's own for this run (as `knitsim simulate`'s);
            // `state` ends as the run's last
            Scene run = s;
            run.model.params =
                params_over(run.model.params,
                            params_and_keywords(py::none(), kw, "run", nullptr, "solver"), "run");
            if (output_every) run.output_every = *output_every;
            if (duration) {
              try {
                check_duration(*duration, run.model.params.solver.time_step);
              } catch (const std::invalid_argument& e) {
                throw std::invalid_argument(std::string("duration: ") + e.what());
              }
              run.duration = *duration;
            }
            SimulateOptions o;
            if (py::isinstance<py::str>(resume)) {
              const std::string path = resume.cast<std::string>();
              require_path(path, "resume");
              const StateFile f = read_state_file(path);
              std::vector<int> counts;
              for (const YarnInfo& y : run.model.yarns) counts.push_back(y.num_cp());
              if (f.yarn_cp_counts != counts)
                throw std::invalid_argument(
                    "resume " + path + ": it holds " + std::to_string(f.yarn_cp_counts.size()) +
                    " yarn(s) and " + std::to_string(f.num_cp()) +
                    " control points, but the scene has " + std::to_string(counts.size()) +
                    " and " + std::to_string(run.model.num_cp()) +
                    ": it is not a state of this scene");
              if (f.state.time >= run.duration - 1e-6 * run.model.params.solver.time_step)
                throw std::invalid_argument(
                    "resume " + path + ": the state is at t = " + short_number(f.state.time) +
                    " s, already at the scene's end (" + short_number(run.duration) +
                    " s): give a longer duration to go on");
              run.state = f.state;
              o.continue_in_place = !out.empty() && resumes_in_place(path, out);
              o.extra["resumed_from"] = path;
            } else if (!resume.is_none()) {
              throw py::type_error("Scene.run: resume is a .kstate path");
            }
            o.out_dir = out;
            o.overwrite = overwrite;
            o.progress = progress;
            o.write_frames = !out.empty();
            o.check_crossings = check_crossings;
            const auto limit = thread_limit(threads);
            py::dict report =
                report_dict(run_interruptible([&] { return simulate_scene(run, o); }));
            s.state = run.state;
            export_outputs(export_format, out, run.model.objects);
            return report;
          },
          "out"_a = "", "overwrite"_a = false, "progress"_a = false, "resume"_a = py::none(),
          "duration"_a = py::none(), "output_every"_a = py::none(), "check_crossings"_a = false,
          "threads"_a = 0, "export"_a = "",
          "Runs the scene to its duration (as `knitsim simulate`); `state` ends as the last "
          "state. Returns the report. `resume`: go on from a .kstate of an earlier run of this "
          "scene (into that run's `out`, the run goes on there). `duration` (s), "
          "`output_every` (steps) and the solver's parameters as keywords (`time_step`, "
          "`integrator`, `implicit_bending`, `contact_solve_tolerance`, `contact_reuse`, "
          "`max_step_halvings`, `refuse_crossings`, …: the solver's group of "
          "docs/parameters.md) override the scene's own for this run; "
          "`threads` (0: as set_threads left it); `export`: also export the run in `out` "
          "(usd: every state as frames.usda; obj, bcc, ply, …: the final state), as "
          "`knitsim simulate --export`.");
  m.def(
      "load_scene",
      [](const std::string& path, const std::string& knit) {
        require_path(path, "path");
        if (knit.empty()) return load_scene(path);
        require_path(knit, "knit");
        return load_scene_with_knit(path, knit);
      },
      "path"_a, "knit"_a = "",
      "Reads a scene file (docs/scene-format.md); `knit`: a .kstate for the scene's knit "
      "(as `knitsim simulate --knit`).");

  // ------------------------------------------------------------- stretch
  const StretchOptions stretch_options;
  const SheetStretchOptions sheet_options;
  static const std::string stretch_doc =
      "Stretch test of a relaxed knit (.kstate) along the course, wale or bias, as `knitsim "
      "stretch --from`: returns the report with `curve` (strain, clamp forces in dyn, width in "
      "cm, … as numpy arrays), the initial clamp separation (cm) and the speed as run. `to`: "
      "nominal strain (default " +
      num(stretch_options.to_strain) + "), `speed` (cm/s, default " + num(stretch_options.speed) +
      "), `cycles` further half-cycles, `clamp_stitches` (default " +
      std::to_string(stretch_options.clamp_stitches) +
      "). `hold` > 0: pull in steps of that strain and hold the clamps still for `hold_time` s "
      "(default " +
      num(stretch_options.hold_time) +
      ") after each (FIRE, or the simulation's damping with `hold_damped`); the samples with "
      "`equilibrium` true are the holds' ends, their forces the clamps' static reactions and "
      "`force_residual` (cm/s²) how far from rest each is. `max_force` > 0 (dyn): end the pull "
      "at the first sample where a clamp's force exceeds it (a load limit; the summary's "
      "stretch.stopped says where). `alpha_small`, `alpha_large` (default " +
      num(stretch_defaults.material.alpha_small) + " and " +
      num(stretch_defaults.material.alpha_large) + " per 1/11800 s), `yarn_friction` (default " +
      num(stretch_defaults.material.yarn_friction) +
      "), `end_mass_floor`, `contact_points` (default " +
      std::to_string(stretch_defaults.discretisation.contact_points) + "). " + solver_doc +
      " Defaults: time step " + num(stretch_defaults.solver.time_step) + " s, integrator " +
      integrator_name(stretch_defaults.solver.integrator) +
      ". `resume`: go on with the stopped run in `out` (same arguments) from its final.kstate, "
      "a frame, or `out` itself (its latest state with a sample in stretch.csv). With `out`: "
      "`frames` (the states along the way) and `render` (renders at strains 0, 0.25, 0.5, 1 "
      "and a movie), as the command writes them. `sheet`: stretch the elastic-sheet model "
      "instead (`knitsim stretch --sheet`), with `k_course`, `k_wale`, `k_shear` (dyn/cm, "
      "default " +
      num(sheet_options.material.k_stretch_u) + ", " + num(sheet_options.material.k_stretch_v) +
      ", " + num(sheet_options.material.k_shear) + "), `k_bend` (erg, default " +
      num(sheet_options.material.k_bend) + ") and `node_spacing` (cm, default " +
      num(sheet_options.node_spacing) +
      "), or those fitted to the yarn stretch runs' directories `fit`. The command's PATTERN "
      "(relaxed first) is relax() and then stretch(); its --plot, plotting.";
  m.def(
      "stretch",
      [](const std::string& kstate, const std::string& direction, double to, double speed,
         int cycles, int clamp_stitches, double output_strain, double hold, double hold_time,
         bool hold_damped, const py::object& params, const std::string& out, bool overwrite,
         bool render, bool progress, const std::string& resume, double max_force, bool frames,
         bool check_crossings, int threads, bool sheet, const std::vector<std::string>& fit,
         std::optional<double> k_course, std::optional<double> k_wale,
         std::optional<double> k_shear, std::optional<double> k_bend,
         std::optional<double> node_spacing, const py::kwargs& kw) {
        StretchOptions o;
        o.resume = resume;
        o.max_force = max_force;
        o.params = params_over(o.params, params_and_keywords(params, kw, "stretch"), "stretch");
        std::set<std::string> keywords;  // the parameters given as keywords
        for (auto item : kw) keywords.insert(item.first.cast<std::string>());
        o.hold_strain = hold;
        o.hold_time = hold_time;
        o.hold_damped = hold_damped;
        o.direction = parse_stretch_direction(direction);
        o.to_strain = to;
        o.speed = speed;
        o.cycles = cycles;
        o.clamp_stitches = clamp_stitches;
        o.output_strain = output_strain;
        o.out_dir = out;
        o.overwrite = overwrite;
        o.render = render;
        o.figures = write_stretch_figures;  // the plots, renders and movie
        o.progress = progress;
        o.write_frames = frames && !out.empty();
        o.check_crossings = check_crossings;
        // the arguments first, then the files they name (as the command checks its options
        // before it reads anything)
        require_path(kstate, "kstate");
        if (!resume.empty()) require_path(resume, "resume");
        const auto limit = thread_limit(threads);
        StretchResult r;
        if (sheet) {
          // as the command: the yarn model's own options have no meaning for the sheet
          std::string yarn_only;
          auto note = [&](bool given, const char* kw) {
            if (given) yarn_only += (yarn_only.empty() ? "" : ", ") + std::string(kw);
          };
          note(hold > 0, "hold");
          note(hold_damped, "hold_damped");
          note(max_force > 0, "max_force");
          // the yarn model's parameters given as keywords (a params dict is the yarn model's
          // too, but the sheet stretch reads its radius from it, as the command does)
          for (const std::string& k : keywords) note(true, k.c_str());
          note(!resume.empty(), "resume");
          if (!yarn_only.empty())
            throw std::invalid_argument(
                "sheet=True: the sheet is pulled through equilibria already; " + yarn_only +
                " are for the yarn model");
          SheetStretchOptions so;
          so.stretch = o;
          if (k_course) so.material.k_stretch_u = *k_course;
          if (k_wale) so.material.k_stretch_v = *k_wale;
          if (k_shear) so.material.k_shear = *k_shear;
          if (k_bend) so.material.k_bend = *k_bend;
          if (node_spacing) so.node_spacing = *node_spacing;
          r = run_interruptible([&] {
            if (!fit.empty()) {
              const SheetFit f = fit_sheet_material(kstate, fit, so);
              so.material = f.material;
              so.fit = f.report;
            }
            return stretch_sheet(kstate, so);
          });
        } else {
          if (!fit.empty() || k_course || k_wale || k_shear || k_bend || node_spacing)
            throw std::invalid_argument(
                "fit, k_course, k_wale, k_shear, k_bend and node_spacing need sheet=True");
          r = run_interruptible([&] { return stretch_knit(kstate, o); });
        }
        const auto n = static_cast<py::ssize_t>(r.curve.size());
        auto column = [&](double StretchSample::*field) {
          py::array_t<double> a(n);
          for (py::ssize_t k = 0; k < n; ++k) a.mutable_at(k) = r.curve[k].*field;
          return a;
        };
        py::dict curve("time"_a = column(&StretchSample::time),
                       "strain"_a = column(&StretchSample::strain),
                       "force_fixed"_a = column(&StretchSample::force_fixed),
                       "force_moving"_a = column(&StretchSample::force_moving),
                       "width"_a = column(&StretchSample::width),
                       "potential_energy"_a = column(&StretchSample::potential_energy),
                       "kinetic_energy"_a = column(&StretchSample::kinetic_energy),
                       "min_contact_distance"_a = column(&StretchSample::min_contact_distance),
                       "edge_curl"_a = column(&StretchSample::edge_curl),
                       "force_residual"_a = column(&StretchSample::force_residual));
        py::array_t<bool> equilibrium(n);
        for (py::ssize_t k = 0; k < n; ++k) equilibrium.mutable_at(k) = r.curve[k].equilibrium;
        curve["equilibrium"] = equilibrium;
        py::dict result = report_dict(r.report);
        result["curve"] = curve;
        result["initial_separation"] = r.initial_separation;
        result["speed"] = r.speed;
        result["axis"] = vec3(r.axis);
        return result;
      },
      "kstate"_a, "direction"_a = stretch_direction_name(stretch_options.direction),
      "to"_a = stretch_options.to_strain, "speed"_a = stretch_options.speed,
      "cycles"_a = stretch_options.cycles, "clamp_stitches"_a = stretch_options.clamp_stitches,
      "output_strain"_a = stretch_options.output_strain, "hold"_a = stretch_options.hold_strain,
      "hold_time"_a = stretch_options.hold_time, "hold_damped"_a = stretch_options.hold_damped,
      "params"_a = py::none(), "out"_a = "", "overwrite"_a = false,
      "render"_a = stretch_options.render, "progress"_a = false, "resume"_a = "",
      "max_force"_a = stretch_options.max_force, "frames"_a = true, "check_crossings"_a = false,
      "threads"_a = 0, "sheet"_a = false, "fit"_a = std::vector<std::string>{},
      "k_course"_a = py::none(), "k_wale"_a = py::none(), "k_shear"_a = py::none(),
      "k_bend"_a = py::none(), "node_spacing"_a = py::none(), stretch_doc.c_str());
}
