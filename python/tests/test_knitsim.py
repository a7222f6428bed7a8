"""The Python module against physics and against the library's own recipes.

Run through ctest (scripts/test.sh), or by hand:
    PYTHONPATH=build/python KNIT_EXAMPLES=examples /usr/bin/python3 -m pytest python/tests
"""
import json
import os
import pathlib
import signal
import threading

import numpy as np
import pytest

import knitsim

EXAMPLES = pathlib.Path(os.environ.get("KNIT_EXAMPLES",
                                       pathlib.Path(__file__).parents[2] / "examples"))
G = 981.0  # cm/s², MODEL.md's gravity


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
    with pytest.raises(ValueError, match="contact-reuse-widen"):
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
    with pytest.raises(ValueError, match="bind-off"):
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
    with pytest.raises(ValueError, match="cast-on"):
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
    with pytest.raises(ValueError, match="max-force"):
        knitsim.stretch(saved_knit, to=0.02, max_force=-1)


def test_errors_are_the_librarys_messages(tmp_path):
    with pytest.raises(ValueError, match="not a built-in pattern"):
        knitsim.relax("no_such_pattern", rows=4, cols=4)
    with pytest.raises(ValueError, match="rows"):
        knitsim.relax("stockinette", rows=1, cols=4)
    with pytest.raises(RuntimeError, match="missing.kstate"):
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


def test_a_knitout_program_of_any_name_is_read_as_knitout(tmp_path):
    # known by its ;!knitout- header, not its extension: a 4 x 4 program named .txt relaxes
    # at its own size (a chart reader would call its ';' an unknown stitch)
    program = tmp_path / "garter.txt"
    program.write_text((pathlib.Path(__file__).parents[2] / "tests" / "data" / "yarns" /
                        "swatch4x4garter.k").read_text())
    k = knitsim.relax(str(program), max_time=0.001)
    assert k.model.knit["rows"] == 4 and k.model.knit["cols"] == 4
