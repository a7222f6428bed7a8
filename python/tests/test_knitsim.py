"""The Python module against physics and against the library's own recipes.

Run through ctest (scripts/test.sh), or by hand:
    PYTHONPATH=build/python KNIT_EXAMPLES=examples /usr/bin/python3 -m pytest python/tests
"""
import json
import os
import pathlib
import re
import signal
import subprocess
import threading

import numpy as np
import pytest

import knitsim

EXAMPLES = pathlib.Path(os.environ.get("KNIT_EXAMPLES",
                                       pathlib.Path(__file__).parents[2] / "examples"))
TEST_DATA = pathlib.Path(__file__).parents[2] / "tests" / "data"
G = 981.0  # cm/s², MODEL.md's gravity
# the knitsim program built beside the module (build/knitsim beside build/python/)
KNITSIM = pathlib.Path(os.environ.get(
    "KNIT_APP", pathlib.Path(knitsim.__file__).resolve().parents[1] / "knitsim"))


@pytest.fixture(scope="module")
def small_knit():
    # a 4×5 stockinette relaxed briefly: enough for layouts, files and a short pull
    return knitsim.relax("stockinette", rows=4, cols=5, max_time=0.03)


def write_scene(tmp_path, scene):
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(scene))
    return str(path)


def test_version_is_the_programs():
    assert knitsim.__version__.count(".") == 2


def test_relax_gives_a_knit_with_its_layout_and_gauge(small_knit):
    k = small_knit
    m, s = k.model, k.state
    assert k.status == "ok"
    assert s.q.shape == (m.num_cp, 3) and s.v.shape == (m.num_cp, 3)
    assert m.stitch.shape == (m.num_seg, 2)
    # every stitch of the 4×5 chart is somewhere in the yarn
    stitches = {tuple(rc) for rc in m.stitch if rc[0] >= 0}
    assert stitches == {(r, c) for r in range(4) for c in range(5)}
    assert m.knit["pattern"] == "stockinette" and m.knit["rows"] == 4
    shape = k.shape
    # the gauge is the fabric's extent per stitch, a few yarn diameters
    assert 4 * m.radius < shape["stitch_width_cm"] < 20 * m.radius
    assert 4 * m.radius < shape["row_height_cm"] < 20 * m.radius
    assert shape == knitsim.measure_fabric(m, s)
    # the summary is the one `knitsim relax` writes
    assert k.summary["status"] == "ok" and k.steps == k.summary["steps"]


def test_the_integrator_and_step_are_parameters():
    k = knitsim.relax("stockinette", rows=4, cols=5, max_time=0.01,
                      params={"integrator": "imex", "time_step": 2e-4})
    assert k.status == "ok" and k.steps == 50
    assert k.model.integrator == "imex" and k.model.time_step == 2e-4
    assert k.summary["params"]["solver"]["integrator"] == "imex"
    assert k.summary["params"]["solver"]["implicit_bending"] is False
    b = knitsim.relax("stockinette", rows=4, cols=5, max_time=0.01,
                      params={"integrator": "imex", "time_step": 2e-4, "implicit_bending": True})
    assert b.status == "ok" and b.summary["params"]["solver"]["implicit_bending"] is True
    with pytest.raises(ValueError, match="integrator"):
        knitsim.relax("stockinette", rows=4, cols=5, max_time=0.01,
                      params={"integrator": "implicit"})


def test_fire_relaxation_rests_by_the_force_residual():
    # FIRE: no damping, rest when the net force per unit mass is below `residual`
    k = knitsim.relax("stockinette", rows=4, cols=4, max_time=0.06, fire=True,
                      residual=1e9, params={"integrator": "imex", "time_step": 3e-4})
    s = k.summary
    assert s["method"] == "fire" and s["rest_test"] == "residual"
    assert s["relaxed"] and s["force_residual"] < 1e9
    assert s["k_global"] == 0.0 and "fire" in s["stage_seconds"]
    with pytest.raises(ValueError, match="residual"):
        knitsim.relax("stockinette", rows=4, cols=4, max_time=0.01, residual=-1.0)


def test_fire_relaxation_widens_the_contact_reuse_far_from_rest():
    reuse = {"integrator": "imex-contact", "time_step": 6e-4, "contact_reuse": 0.05}
    k = knitsim.relax("garter", rows=3, cols=3, max_time=0.03, fire=True, params=reuse,
                      contact_reuse_widen=3.0, contact_reuse_widen_residual=1.0)
    s = k.summary
    assert s["contact_reuse_widen"] == {"max": 3.0, "residual": 1.0}
    assert 2.0 < s["contact_reuse_scale_mean"] <= 3.0
    with pytest.raises(ValueError, match="contact_reuse_widen = 2 .*give contact_reuse "):
        knitsim.relax("garter", rows=3, cols=3, max_time=0.01, contact_reuse_widen=2.0)

def test_bind_off_ties_the_last_row(tmp_path):
    # a bound-off knit: two ties per loop of its last row beside the ends' two glues,
    # and its state file says so
    k = knitsim.relax("stockinette", rows=3, cols=4, max_time=0.002, bind_off=True,
                      out=str(tmp_path / "b"))
    assert k.summary["bind_off"] is True
    f = knitsim.read_state(str(tmp_path / "b" / "relaxed.kstate"))
    assert f.knit["bind_off"] is True
    assert knitsim.relax("stockinette", rows=3, cols=4, max_time=0.002).summary["bind_off"] is False
    # resumed from its file, the knit keeps its pattern, size and bind-off; a mismatch is
    # refused naming it
    again = knitsim.relax(resume=str(tmp_path / "b" / "relaxed.kstate"), max_time=0.002)
    assert again.summary["bind_off"] is True and again.summary["pattern"] == "stockinette"
    assert again.summary["rows"] == 3 and again.summary["cols"] == 4
    with pytest.raises(ValueError, match="bind_off=True"):
        knitsim.relax(resume=str(tmp_path / "b" / "relaxed.kstate"), bind_off=False,
                      max_time=0.002)
    with pytest.raises(TypeError, match="resume"):
        knitsim.relax("stockinette", resume=3)


def test_cast_on_ties_the_first_row(tmp_path):
    # a cast-on knit: two ties per loop of its second row; kept on resume, checked
    k = knitsim.relax("garter", rows=3, cols=4, max_time=0.002, cast_on=True,
                      out=str(tmp_path / "c"))
    assert k.summary["cast_on"] is True and k.summary["bind_off"] is False
    f = knitsim.read_state(str(tmp_path / "c" / "relaxed.kstate"))
    assert f.knit["cast_on"] is True
    again = knitsim.relax(resume=str(tmp_path / "c" / "relaxed.kstate"), max_time=0.002)
    assert again.summary["cast_on"] is True
    with pytest.raises(ValueError, match="cast_on=True"):
        knitsim.relax(resume=str(tmp_path / "c" / "relaxed.kstate"), cast_on=False,
                      max_time=0.002)


def test_state_arrays_are_views_of_the_state(small_knit):
    s = small_knit.state.copy()
    q = s.q
    q[0, 0] += 1.0
    assert s.q[0, 0] == q[0, 0]  # the same memory
    before = s.q.copy()
    s.q = before + 2.0  # assignment copies in
    assert np.array_equal(s.q, before + 2.0)
    with pytest.raises(ValueError, match="points for a state of"):
        s.q = np.zeros((3, 3))


def test_kstate_files_round_trip_exactly(small_knit, tmp_path):
    path = str(tmp_path / "knit.kstate")
    small_knit.save(path)
    f = knitsim.read_state(path)
    assert np.array_equal(f.state.q, small_knit.state.q)
    assert np.array_equal(f.state.v, small_knit.state.v)
    assert f.state.time == small_knit.state.time
    assert np.array_equal(f.stitch, small_knit.model.stitch)
    assert f.yarn_cp_counts == small_knit.model.yarn_cp_counts
    assert f.knit["cols"] == 5


def test_a_free_yarn_falls_at_g_and_keeps_its_momentum_otherwise(tmp_path):
    # no pins, no damping: the centre of mass accelerates at exactly g (MODEL.md's
    # internal forces and the length projection exert no net force)
    scene = write_scene(tmp_path, {
        "time_step": 1e-4, "duration": 0.05,
        "params": {"k_global": 0, "contact": False},
        "yarns": [{"polyline": [[0, 0, 0], [2, 1, 0], [4, 0, 1], [6, 1, 1]], "segments": 12}],
    })
    sc = knitsim.load_scene(scene)
    sim = sc.simulator()
    s = sc.state
    mass = sc.model.mass
    sim.step(s, steps=500)
    assert s.time == pytest.approx(0.05)
    momentum = (mass[:, None] * s.v).sum(axis=0)
    vcm = momentum / mass.sum()
    assert vcm[2] == pytest.approx(-G * 0.05, rel=1e-9)
    assert abs(vcm[0]) < 1e-9 and abs(vcm[1]) < 1e-9
    assert np.allclose(sim.linear_momentum(s), momentum)


def test_force_residual_is_small_at_rest_and_says_where_it_sits():
    # the settled catenary is at rest: its net unheld force per unit mass is a tiny part of
    # g; pulling one control point aside leaves a residual, largest where it was pulled
    sc = knitsim.load_scene(str(EXAMPLES / "hanging.json"))
    assert sc.run()["status"] == "ok"
    sim = sc.simulator()
    rest = sim.force_residual(sc.state)
    assert rest < 1e-2 * G
    data = sim.data
    assert data["force_residual"] == pytest.approx(rest)
    assert data["force_residual_peak"]["acceleration"] >= rest
    moved = sc.state.copy()
    k = len(sc.model.mass) // 2
    q = moved.q
    q[k, 0] += 0.05
    pulled = sim.force_residual(moved)
    assert pulled > 10 * rest
    peak = sim.data["force_residual_peak"]
    assert abs(peak["control_point"] - k) <= 3  # a point sharing a segment with it
    assert 0.01 <= peak["top_percent_share"] <= 1.0
    sim.step(moved)  # a step's data describes no residual until one is asked for
    assert sim.data["force_residual"] is None and sim.data["force_residual_peak"] is None


def test_pins_carry_the_weight_of_a_hanging_yarn():
    # the catenary example settles; its two pins then hold the yarn's whole weight
    sc = knitsim.load_scene(str(EXAMPLES / "hanging.json"))
    report = sc.run()
    assert report["status"] == "ok"
    sim = sc.simulator()
    sim.step(sc.state)
    data = sim.data
    pins = [c for c in data["constraints"] if c["kind"] == "pin"]
    assert len(pins) == 2
    lift = sum(c["force"][2] for c in pins)
    weight = sc.model.mass.sum() * G
    assert lift == pytest.approx(weight, rel=0.01)
    # and they pull the ends together equally (a symmetric catenary)
    assert pins[0]["force"][0] == pytest.approx(-pins[1]["force"][0], rel=0.01)
    assert data["energies"]["gravity"] < 0 and data["kinetic_energy"] < 1e-3 * abs(
        data["energies"]["gravity"])


def test_stepping_by_hand_matches_the_scene_run():
    a = knitsim.load_scene(str(EXAMPLES / "pendulum.json"))
    a.duration = 0.01
    a.run()
    b = knitsim.load_scene(str(EXAMPLES / "pendulum.json"))
    sim = b.simulator()
    sim.step(b.state, steps=100)
    assert b.state.time == pytest.approx(a.state.time)
    assert np.allclose(b.state.q, a.state.q, rtol=0, atol=1e-12)


def test_contact_set_reads_as_arrays(small_knit):
    sim = knitsim.Simulator(small_knit.model)
    sim.forward(small_knit.state)
    c = sim.data["contact"]
    assert c["present"] and len(c["seg_i"]) > 0
    assert (c["seg_i"] < c["seg_j"]).all()
    assert ((c["d"] > 0) & (c["d"] < 1)).all()
    assert np.allclose(np.linalg.norm(c["normal"], axis=1), 1.0)
    assert c["min_distance_ratio"] <= c["d"].min() + 1e-12
    assert ((c["t_i"] >= 0) & (c["t_i"] <= 1) & (c["t_j"] >= 0) & (c["t_j"] <= 1)).all()
    assert not sim.data["friction"]["present"]  # no yarn friction asked for


@pytest.fixture
def saved_knit(small_knit, tmp_path):
    path = str(tmp_path / "knit.kstate")
    small_knit.save(path)
    return path


def test_stretch_returns_its_curve(saved_knit):
    r = knitsim.stretch(saved_knit, direction="course", to=0.05, speed=5.0, output_strain=0.01)
    assert r["status"] == "ok"
    curve = r["curve"]
    assert curve["strain"][0] == pytest.approx(0, abs=1e-9)
    assert curve["strain"][-1] == pytest.approx(0.05, abs=1e-3)
    assert r["initial_separation"] > 0
    # the sample resists: both clamps pull it apart at the end
    assert curve["force_moving"][-1] > 0 and curve["force_fixed"][-1] > 0


def test_stretch_with_held_clamps_samples_the_holds(saved_knit):
    r = knitsim.stretch(saved_knit, direction="course", to=0.1, hold=0.05, hold_time=0.02)
    assert r["status"] == "ok"
    curve = r["curve"]
    # the unrelaxed start, then the ends of the holds at strain 0, 0.05 and 0.1
    assert list(curve["equilibrium"]) == [False, True, True, True]
    assert curve["strain"][1:] == pytest.approx([0, 0.05, 0.1], abs=1e-9)
    assert all(curve["force_residual"] >= 0)


def test_stretch_takes_parameters_such_as_yarn_friction(saved_knit):
    r = knitsim.stretch(saved_knit, to=0.02, params={"yarn_friction": 0.3, "end_mass_floor": 0.5})
    assert r["status"] == "ok"
    assert r["curve"]["force_moving"][-1] > 0
    with pytest.raises(ValueError, match="yarn_friction"):
        knitsim.stretch(saved_knit, to=0.02, params={"yarn_friction": -1})
    with pytest.raises(ValueError, match="end_mass_floor"):
        knitsim.stretch(saved_knit, to=0.02, params={"end_mass_floor": 2})


def test_stretch_stops_at_a_load_limit(saved_knit):
    whole = knitsim.stretch(saved_knit, direction="course", to=0.05)
    limit = 0.95 * max(whole["curve"]["force_moving"])
    r = knitsim.stretch(saved_knit, direction="course", to=0.05, max_force=limit)
    assert r["status"] == "ok"
    stop = r["summary"]["stretch"]["stopped"]
    assert stop["reason"] == "max_force" and stop["strain"] < 0.05
    assert max(stop["force_moving_dyn"], stop["force_fixed_dyn"]) > limit
    assert all(r["curve"]["force_moving"][:-1] <= limit)
    with pytest.raises(ValueError, match="max_force"):
        knitsim.stretch(saved_knit, to=0.02, max_force=-1)


def test_errors_are_the_librarys_messages(tmp_path):
    with pytest.raises(ValueError, match="not a built-in pattern"):
        knitsim.relax("no_such_pattern", rows=4, cols=4)
    with pytest.raises(ValueError, match="rows"):
        knitsim.relax("stockinette", rows=1, cols=4)
    with pytest.raises(FileNotFoundError, match="missing.kstate"):
        knitsim.read_state(str(tmp_path / "missing.kstate"))
    bad = tmp_path / "bad.json"
    bad.write_text('{"yarns": [}')
    with pytest.raises(ValueError, match="bad.json"):
        knitsim.load_scene(str(bad))
    with pytest.raises(ValueError, match="direction"):
        knitsim.stretch(str(tmp_path / "x.kstate"), direction="up")


def test_a_failing_step_raises_and_keeps_the_state():
    sc = knitsim.load_scene(str(EXAMPLES / "pendulum.json"))
    sim = sc.simulator()
    before = sc.state.q.copy()
    with pytest.raises(knitsim.StepError):
        sim.step(sc.state, h=1e9)
    assert np.array_equal(sc.state.q, before)


def test_ctrl_c_ends_a_relaxation_after_a_step(tmp_path):
    # SIGINT while relaxing: the run stops cleanly (its state written) and Python gets
    # KeyboardInterrupt
    timer = threading.Timer(1.0, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    out = tmp_path / "run"
    with pytest.raises(KeyboardInterrupt):
        knitsim.relax("stockinette", rows=6, cols=6, max_time=100.0, out=str(out))
    timer.join()
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted"
    assert (out / "final.kstate").exists()


def test_resume_goes_on_as_the_relaxation_went(tmp_path):
    # a FIRE relaxation's state says how it was relaxing; resumed from its path alone it
    # goes on the same way, step for step as naming everything again; an argument wins
    params = {"integrator": "imex-contact", "time_step": 6e-4, "contact_reuse": 0.05}
    knitsim.relax("garter", rows=3, cols=3, max_time=0.015, fire=True, params=params,
                  contact_reuse_widen=2.0, out=str(tmp_path / "a"))
    first = str(tmp_path / "a" / "final.kstate")
    relaxation = knitsim.read_state(first).knit["relaxation"]
    assert relaxation["fire"] is True and relaxation["integrator"] == "imex-contact"
    assert relaxation["time_step"] == 6e-4 and relaxation["contact_reuse_widen"] == 2.0
    alone = knitsim.relax(resume=first, max_time=0.015)
    named = knitsim.relax("garter", rows=3, cols=3, resume=first, max_time=0.015, fire=True,
                          params=params, contact_reuse_widen=2.0)
    assert alone.summary["method"] == "fire" and alone.summary["steps"] == 25
    assert alone.summary["params"]["solver"]["integrator"] == "imex-contact"
    assert np.array_equal(alone.state.q, named.state.q)
    damped = knitsim.relax(resume=first, max_time=0.015, fire=False)
    assert damped.summary["method"] == "damped_dynamics"
    other = knitsim.relax(resume=first, max_time=0.006, params={"time_step": 5e-4})
    assert other.summary["params"]["solver"]["time_step"] == 5e-4
    # another integrator leaves the file's contact reuse (imex-contact's) and its widening
    imex = knitsim.relax(resume=first, max_time=0.006, params={"integrator": "imex"})
    assert imex.summary["params"]["solver"]["contact_reuse"] == 0.0
    assert "contact_reuse_widen" not in imex.summary


# ---------------------------------------------------------------- the commands' options

def cli(*args):
    if not KNITSIM.exists():
        pytest.skip(f"no knitsim program at {KNITSIM}")
    return subprocess.run([str(KNITSIM), *map(str, args)], capture_output=True, text=True)


def cli_options(command):
    """The long option names `knitsim COMMAND --help` lists, without their dashes."""
    names = []
    for line in cli(command, "--help").stdout.splitlines():
        if line.startswith("  ") and not line.startswith("   "):
            for name in line[2:].split("  ")[0].split(" ")[0].split(","):
                if name.startswith("--") and name != "--help":
                    names.append(name[2:])
    return names


PARAMETERS = {p["name"] for p in knitsim.parameters()}


def signature(function):
    return function.__doc__.splitlines()[0]


def keywords(function):
    """The keyword arguments of a module function, from its signature line."""
    return set(re.findall(r"(\w+): ", function.__doc__.splitlines()[0]))


# the options spelt otherwise in Python (docs/cli.md, "From Python")
SPELT = {"round": "in_the_round", "ke-threshold": "rest", "quiet": "progress",
         "no-frames": "frames", "no-render": "render", "no-fire": "fire",
         "no-implicit-bending": "implicit_bending", "no-refuse-crossings": "refuse_crossings"}


def test_python_takes_every_option_of_the_commands():
    # each command's options are keywords of the function that stands for it; the few
    # that belong elsewhere in Python say where
    elsewhere = {
        "relax": {"from": None, "scale": knitsim.relax_yarns},  # relax_yarns(path, …)
        "simulate": {"knit": knitsim.load_scene},
        # a PATTERN is relaxed first by relax(); --plot draws runs, which Python plots itself
        "stretch": {"from": None, "plot": None, "rows": knitsim.relax, "cols": knitsim.relax,
                    "bind-off": knitsim.relax, "cast-on": knitsim.relax, "relax-time": None},
    }
    functions = {"relax": knitsim.relax, "simulate": knitsim.Scene.run,
                 "stretch": knitsim.stretch}
    for command, function in functions.items():
        options = cli_options(command)
        assert len(options) > 10, command
        for option in options:
            target = elsewhere.get(command, {}).get(option, function)
            if target is None:
                continue
            kw = SPELT.get(option, option.replace("-", "_"))
            # a parameter of the model is a keyword of every function (its **kwargs)
            assert kw in keywords(target) or (kw in PARAMETERS and "**kwargs" in signature(target)), \
                f"{command} --{option}: no keyword {kw}"
    # relax_yarns takes what `relax --from` takes
    for option in ("scale", "shrink", "max-time", "check-every", "threads", "export"):
        assert option.replace("-", "_") in keywords(knitsim.relax_yarns), option
    for option in ("time-step", "integrator", "k-global"):  # parameters
        assert option.replace("-", "_") in PARAMETERS
        assert "**kwargs" in signature(knitsim.relax_yarns)


def test_every_parameter_is_a_keyword():
    # the parameter table, as Python reads it: each parameter, its group, unit and range
    table = knitsim.parameters()
    names = {p["name"] for p in table}
    assert {"radius", "k_bend", "time_step", "integrator", "refuse_crossings"} <= names
    for p in table:
        assert p["group"] in ("material", "discretisation", "solver"), p
        if "min" in p:
            assert p["min"] <= p["default"] <= p["max"], p
    integrator = next(p for p in table if p["name"] == "integrator")
    assert integrator["default"] in integrator["choices"]
    # any parameter is a keyword of relax, relax_yarns and stretch (not only those the
    # commands' options name): k_bend here, which no option of relax sets
    k = knitsim.relax("stockinette", rows=3, cols=3, max_time=0.001, k_bend=4.0)
    assert k.summary["params"]["material"]["k_bend"] == 4.0
    # a parameter's range is checked as in `params`, and a keyword that is neither an
    # argument nor a parameter is named
    with pytest.raises(ValueError, match="k_bend"):
        knitsim.relax("stockinette", rows=3, cols=3, max_time=0.001, k_bend=-1.0)
    with pytest.raises(TypeError, match="k_bent"):
        knitsim.relax("stockinette", rows=3, cols=3, max_time=0.001, k_bent=4.0)
    # a scene's run changes the solver's parameters only: the model is built
    scene = knitsim.load_scene(str(EXAMPLES / "pendulum.json"))
    with pytest.raises(ValueError, match="radius is a material parameter"):
        scene.run(duration=0.001, radius=0.2)


def same_run(summary, other):
    for key in ("params", "steps", "status"):
        assert summary[key] == other[key], key


def test_relax_has_the_commands_defaults(tmp_path):
    out = tmp_path / "cli"
    r = cli("relax", "stockinette", "--rows", 3, "--cols", 4, "--max-time", 0.003, "--out", out,
            "--quiet")
    assert r.returncode == 0, r.stderr
    by_cli = json.loads((out / "summary.json").read_text())
    k = knitsim.relax("stockinette", rows=3, cols=4, max_time=0.003)
    same_run(k.summary, by_cli)
    for key in ("method", "rest_test", "ke_per_length_threshold", "shrink", "k_global"):
        assert k.summary.get(key) == by_cli.get(key), key
    cli_state = knitsim.read_state(str(out / "final.kstate")).state
    assert np.allclose(k.state.q, cli_state.q, rtol=0, atol=1e-9)


def test_stretch_and_simulate_have_the_commands_defaults(saved_knit, tmp_path):
    out = tmp_path / "pull"
    r = cli("stretch", "--from", saved_knit, "--to", 0.02, "--out", out, "--no-render", "--quiet")
    assert r.returncode == 0, r.stderr
    by_cli = json.loads((out / "summary.json").read_text())
    same_run(knitsim.stretch(saved_knit, to=0.02)["summary"], by_cli)
    scene = str(EXAMPLES / "pendulum.json")
    out = tmp_path / "sim"
    r = cli("simulate", scene, "--duration", 0.01, "--out", out, "--quiet")
    assert r.returncode == 0, r.stderr
    by_cli = json.loads((out / "summary.json").read_text())
    sc = knitsim.load_scene(scene)
    same_run(sc.run(duration=0.01)["summary"], by_cli)


def test_relax_takes_the_solver_and_damping_options(tmp_path):
    k = knitsim.relax("stockinette", rows=3, cols=3, max_time=0.004, integrator="imex",
                      time_step=2e-4, implicit_bending=True, max_step_halvings=2,
                      contact_points=8, end_mass_floor=0.5, k_global=1.5, alpha_small=0.5,
                      alpha_large=0.2, check_every=5, threads=1, out=str(tmp_path / "r"),
                      frames=False, export="obj")
    assert k.status == "ok" and k.steps == 20
    p = k.summary["params"]
    assert p["solver"]["integrator"] == "imex" and p["solver"]["time_step"] == 2e-4
    assert p["solver"]["implicit_bending"] is True and p["solver"]["max_step_halvings"] == 2
    assert p["discretisation"] == {**p["discretisation"], "contact_points": 8,
                                   "end_mass_floor": 0.5}
    assert (p["material"]["k_global"], p["material"]["alpha_small"],
            p["material"]["alpha_large"]) == (1.5, 0.5, 0.2)
    assert (tmp_path / "r" / "final.obj").exists()  # --export
    assert not (tmp_path / "r" / "frames").exists()  # --no-frames
    # a keyword wins over the same parameter in `params`
    k = knitsim.relax("stockinette", rows=3, cols=3, max_time=0.002, params={"time_step": 1e-4},
                      time_step=2e-4, integrator="imex")
    assert k.summary["params"]["solver"]["time_step"] == 2e-4


def test_relax_yarns_relaxes_a_yarn_file():
    k = knitsim.relax_yarns(str(TEST_DATA / "yarns" / "knit-2x2.yarns"), max_time=0.001)
    assert k.status == "ok"
    # imported swatches start tightly packed: the recipe's smaller step
    assert k.summary["params"]["solver"]["time_step"] == pytest.approx(1 / 25000)
    assert k.model.num_cp > 0


def test_scene_run_takes_the_simulate_options(tmp_path):
    sc = knitsim.load_scene(str(EXAMPLES / "pendulum.json"))
    h, duration = sc.model.time_step, sc.duration
    r = sc.run(duration=0.01, time_step=h / 2, integrator="imex", max_step_halvings=2,
               output_every=10, threads=1, out=str(tmp_path / "a"), export="usd")
    assert r["status"] == "ok" and r["steps"] == round(0.01 / (h / 2))
    solver = r["summary"]["params"]["solver"]
    assert solver["time_step"] == h / 2 and solver["integrator"] == "imex"
    assert solver["max_step_halvings"] == 2
    assert (tmp_path / "a" / "frames.usda").exists()
    # the options were this run's: the scene keeps its own, its state is the run's last
    assert sc.model.time_step == h and sc.duration == duration
    assert sc.state.time == pytest.approx(0.01)
    # resumed from the state it wrote, a run goes on to a longer duration
    again = knitsim.load_scene(str(EXAMPLES / "pendulum.json"))
    r = again.run(resume=str(tmp_path / "a" / "final.kstate"), duration=0.02, time_step=h / 2,
                  out=str(tmp_path / "b"))
    assert r["status"] == "ok" and again.state.time == pytest.approx(0.02)
    with pytest.raises(ValueError, match="^resume .*already at the scene's end"):
        again.run(resume=str(tmp_path / "a" / "final.kstate"), duration=0.01)
    with pytest.raises(ValueError, match="^duration: "):
        again.run(duration=-1)


def test_stretch_takes_the_commands_options(saved_knit):
    r = knitsim.stretch(saved_knit, to=0.02, time_step=5e-5, alpha_small=0.5, alpha_large=0.2,
                        yarn_friction=0.3, contact_points=8, end_mass_floor=0.5,
                        max_step_halvings=1, threads=1)
    assert r["status"] == "ok"
    p = r["summary"]["params"]
    assert p["solver"]["time_step"] == 5e-5 and p["solver"]["max_step_halvings"] == 1
    assert (p["material"]["alpha_small"], p["material"]["alpha_large"],
            p["material"]["yarn_friction"]) == (0.5, 0.2, 0.3)
    assert (p["discretisation"]["contact_points"], p["discretisation"]["end_mass_floor"]) == (8, 0.5)
    # the elastic sheet, as `stretch --sheet` (on a knit wide enough for its grid)
    sheet = knitsim.stretch(str(EXAMPLES / "knits" / "stockinette_12x12.kstate"), to=0.05,
                            sheet=True, k_course=2e4, node_spacing=0.6)
    assert sheet["status"] == "ok" and sheet["summary"]["model"] == "sheet"
    assert sheet["summary"]["sheet"]["material"]["k_stretch_u_dyn_per_cm"] == 2e4
    assert sheet["summary"]["sheet"]["node_spacing_cm"] == 0.6
    assert sheet["curve"]["force_moving"][-1] > 0


def test_errors_name_the_keyword_not_the_option(saved_knit, tmp_path):
    cases = [
        (lambda: knitsim.relax("stockinette", rows=1, cols=4), "rows"),
        (lambda: knitsim.relax("stockinette", rows=3, cols=3, max_time=-1), "max_time"),
        (lambda: knitsim.relax("stockinette", rows=3, cols=3, rest=-1.0), "rest"),
        (lambda: knitsim.relax("stockinette", rows=3, cols=3, time_step=1.0), "time_step"),
        (lambda: knitsim.relax("stockinette", rows=3, cols=3, integrator="implicit"),
         "integrator"),
        (lambda: knitsim.relax("stockinette", rows=3, cols=3, check_every=0), "check_every"),
        (lambda: knitsim.relax("stockinette", rows=3, cols=3, fire=True, alpha_small=0.5),
         "alpha_small"),
        (lambda: knitsim.relax("stockinette", rows=3, cols=3, out=str(tmp_path / "x"),
                               export="stl"), "export"),
        (lambda: knitsim.stretch(saved_knit, to=20), "to"),
        (lambda: knitsim.stretch(saved_knit, to=0.02, speed=0), "speed"),
        (lambda: knitsim.stretch(saved_knit, to=0.1, hold=0.05, hold_time=-1), "hold_time"),
        (lambda: knitsim.stretch(saved_knit, to=0.02, clamp_stitches=0), "clamp_stitches"),
        (lambda: knitsim.stretch(saved_knit, to=0.02, sheet=True, yarn_friction=0.3),
         "yarn_friction"),
        (lambda: knitsim.stretch(saved_knit, to=0.02, k_course=1e4), "k_course"),
    ]
    for call, kw in cases:
        with pytest.raises(ValueError) as e:
            call()
        message = str(e.value)
        assert re.search(rf"\b{kw}\b", message), (kw, message)
        assert " --" not in message and not message.startswith("--"), message


def test_a_missing_file_raises_file_not_found_naming_the_keyword(saved_knit, tmp_path):
    missing = str(tmp_path / "missing.kstate")
    pendulum = str(EXAMPLES / "pendulum.json")
    cases = [
        (lambda: knitsim.read_state(missing), "path"),
        (lambda: knitsim.relax(resume=missing), "resume"),
        (lambda: knitsim.load_scene(str(tmp_path / "missing.json")), "path"),
        (lambda: knitsim.load_scene(pendulum, knit=missing), "knit"),
        (lambda: knitsim.load_scene(pendulum).run(resume=missing), "resume"),
        (lambda: knitsim.stretch(missing, to=0.02), "kstate"),
        (lambda: knitsim.stretch(saved_knit, to=0.02, out=str(tmp_path / "o"), resume=missing),
         "resume"),
        (lambda: knitsim.relax_yarns(str(tmp_path / "missing.yarns")), "path"),
    ]
    for call, kw in cases:
        with pytest.raises(FileNotFoundError, match=rf"^{kw}: .*missing"):
            call()


def test_a_knitout_program_of_any_name_is_read_as_knitout(tmp_path):
    # known by its ;!knitout- header, not its extension: a 4 x 4 program named .txt relaxes
    # at its own size (a chart reader would call its ';' an unknown stitch)
    program = tmp_path / "garter.txt"
    program.write_text((pathlib.Path(__file__).parents[2] / "tests" / "data" / "yarns" /
                        "swatch4x4garter.k").read_text())
    k = knitsim.relax(str(program), max_time=0.001)
    assert k.model.knit["rows"] == 4 and k.model.knit["cols"] == 4


def test_knit_graph_reads_a_program_as_the_command_prints_it():
    # the purl letter k on stockinette: one yarn, every loop held, relax lays it
    path = str(TEST_DATA / "knitout" / "k.knitout")
    g = knitsim.knit_graph(path, loops=True)
    printed = json.loads(subprocess.run([str(KNITSIM), "graph", path, "--loops"],
                                        capture_output=True, text=True, check=True).stdout)
    assert g == printed
    assert len(g["yarns"]) == 1
    assert g["loops"]["total"] == len(g["loop_list"])
    assert g["sheet"] == {"laid": True, "rows": 11, "cols": 14, "in_the_round": False,
                          "first_row_leftward": True}
    # each loop's parents were made before it
    assert all(p < l["id"] for l in g["loop_list"] for p in l["parents"])
    # a program relax cannot lay says why, with its line
    d = knitsim.knit_graph(str(TEST_DATA / "knitout" / "decrease.knitout"))
    assert d["sheet"]["laid"] is False and ":140: " in d["sheet"]["why_not"]
    with pytest.raises(FileNotFoundError, match="no_such.k"):
        knitsim.knit_graph("no_such.k")


def test_runs_check_crossings_when_asked(small_knit):
    k = knitsim.relax("stockinette", rows=4, cols=4, max_time=0.005, check_crossings=True)
    c = k.summary["crossings"]
    assert c["steps_checked"] == k.summary["steps"] and c["count"] == 0 and c["first"] is None
