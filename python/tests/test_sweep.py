"""Sweeps on a local Dask cluster (python/knitsim_sweep.py): the same results as the jobs run
one by one, every result once when a worker is killed mid-job, nothing run twice on a
restart, and each job's own error in its row."""
import json
import os
import signal
import subprocess
import threading
import time

import numpy as np
import pytest

import knitsim
import knitsim_sweep

BUILD_KNITSIM = os.path.join(os.path.dirname(knitsim.__file__), "..", "knitsim")

SIX = {"kind": "relax", "args": {"rows": 3, "cols": 3, "max_time": 0.002},
       "grid": {"pattern": ["stockinette", "garter", "rib1x1"], "stitch_size": [4.0, 4.5]}}


def final_q(out, job):
    return knitsim.read_state(os.path.join(out, "jobs", job["id"], "run", "final.kstate")).state.q


def test_a_sweep_on_two_workers_is_the_jobs_run_one_by_one(tmp_path):
    out = str(tmp_path / "sweep")
    table = knitsim.sweep(SIX, out, workers=2)
    jobs = knitsim_sweep.expand(SIX)
    assert len(jobs) == 6 and list(table["id"]) == [j["id"] for j in jobs]
    assert (table["status"] == "ok").all()
    assert os.path.exists(os.path.join(out, "results.csv"))
    for job in jobs:
        # the same call here, in this process, with all its threads
        k = knitsim.relax(**job["args"])
        assert np.array_equal(final_q(out, job), k.state.q), job["id"]  # bit for bit
        row = table[table["id"] == job["id"]].iloc[0]
        assert row["steps"] == k.steps
        assert row["course_extent_cm"] == k.summary["course_extent_cm"]
    # restarted: nothing runs again (no state is rewritten), the table is the same
    stamps = {j["id"]: os.stat(os.path.join(out, "jobs", j["id"], "run", "final.kstate")).st_mtime_ns
              for j in jobs}
    again = knitsim.sweep(SIX, out, workers=2)
    assert again.equals(table)
    for j in jobs:
        path = os.path.join(out, "jobs", j["id"], "run", "final.kstate")
        assert os.stat(path).st_mtime_ns == stamps[j["id"]], j["id"]


def test_a_worker_killed_mid_job_has_its_job_run_again_once(tmp_path):
    # six jobs, one long enough to be killed while it runs: the process that holds its run
    # directory (the marker's second line names it) is killed, its worker's nanny starts a
    # new worker, the scheduler runs the job again, and the sweep ends with every job once
    spec = {"kind": "relax", "args": {"rows": 3, "cols": 3, "max_time": 0.002},
            "grid": {"pattern": ["stockinette", "garter", "rib1x1"], "stitch_size": [4.0, 4.5]},
            "jobs": [{"pattern": "seed", "rows": 8, "cols": 8, "max_time": 0.15}]}
    jobs = knitsim_sweep.expand(spec)
    long_job = jobs[-1]
    out = str(tmp_path / "sweep")
    marker = os.path.join(out, "jobs", long_job["id"], "run", ".knitsim-run")
    killed = []

    def kill_when_running():
        deadline = time.time() + 60
        while time.time() < deadline and not killed:
            try:
                with open(marker) as f:
                    f.readline()
                    holder = json.loads(f.readline())
                pid = holder["pid"]
                time.sleep(0.3)  # well into the relaxation
                os.kill(pid, signal.SIGKILL)
                killed.append(pid)
            except (FileNotFoundError, ValueError, KeyError):
                time.sleep(0.02)

    killer = threading.Thread(target=kill_when_running)
    killer.start()
    table = knitsim.sweep(spec, out, workers=2)
    killer.join()
    assert killed, "the long job's process was never seen"
    with pytest.raises(ProcessLookupError):
        os.kill(killed[0], 0)  # it is gone
    assert sorted(table["id"]) == sorted(j["id"] for j in jobs)  # each once
    assert (table["status"] == "ok").all(), table[["id", "status"]]
    # it ran again after the kill, in another process: the run directory's marker names it
    with open(marker) as f:
        f.readline()
        assert json.loads(f.readline())["pid"] != killed[0]
    # the job run again gives what it gives when it is not interrupted
    k = knitsim.relax(**long_job["args"])
    assert np.array_equal(final_q(out, long_job), k.state.q)
    with open(os.path.join(out, "results.csv")) as f:
        assert len(f.read().strip().splitlines()) == 1 + len(jobs)


def test_mistakes_are_refused_or_reported_in_their_job(tmp_path):
    spec = {"args": {"rows": 3, "cols": 3, "max_time": 0.002},
            "jobs": [{"pattern": "stockinette"}, {"pattern": "no_such_pattern"},
                     {"pattern": "garter", "rows": 1}, {"pattern": "rib1x1", "k_bend": -1},
                     {"kind": "stretch", "pattern": "seed", "rows": 6, "cols": 6, "to": 0.01,
                      "speed": 5,
                      "render": False}]}
    table = knitsim.sweep(spec, str(tmp_path / "s"), workers=2)
    status = dict(zip(table["id"], table["status"]))
    errors = dict(zip(table["id"], table["error"]))
    ids = [j["id"] for j in knitsim_sweep.expand(spec)]
    assert status[ids[0]] == "ok" and status[ids[4]] == "ok"
    assert "no_such_pattern" in errors[ids[1]]
    assert "rows" in errors[ids[2]]
    assert "k_bend" in errors[ids[3]]
    assert table[table["id"] == ids[4]].iloc[0]["max_strain"] > 0
    # failed jobs leave no result: a restart tries them again
    for i in ids[1:4]:
        assert not os.path.exists(tmp_path / "s" / "jobs" / i / "result.json")
    # a spec that cannot be read is refused before anything runs
    with pytest.raises(knitsim_sweep.SpecError, match="unknown keys"):
        knitsim.sweep({"job": []}, str(tmp_path / "t"))
    with pytest.raises(knitsim_sweep.SpecError, match="kind 'bake'"):
        knitsim.sweep({"kind": "bake"}, str(tmp_path / "t"))
    # a directory of someone else's files is not a sweep's: nothing is written there
    theirs = tmp_path / "theirs"
    theirs.mkdir()
    (theirs / "notes.txt").write_text("mine")
    with pytest.raises(knitsim_sweep.SpecError, match="not a sweep's"):
        knitsim.sweep(SIX, str(theirs))
    assert sorted(os.listdir(theirs)) == ["notes.txt"]


def test_the_stretch_jobs_of_one_knit_share_its_relaxation(tmp_path):
    spec = {"kind": "stretch", "args": {"pattern": "stockinette", "rows": 6, "cols": 6,
                                        "max_time": 0.002, "to": 0.01, "render": False},
            "grid": {"direction": ["course", "wale"]}}
    out = str(tmp_path / "s")
    table = knitsim.sweep(spec, out, workers=2)
    assert (table["status"] == "ok").all()
    assert len(os.listdir(os.path.join(out, "relaxed"))) == 1  # relaxed once
    assert table["relax_course_extent_cm"].nunique() == 1
    # each pull is the pull of that relaxed state, run on its own
    jobs = knitsim_sweep.expand(spec)
    relaxed = os.path.join(out, "relaxed", jobs[0]["relax"]["id"], "run", "final.kstate")
    for job in jobs:
        r = knitsim.stretch(relaxed, **job["args"])
        row = table[table["id"] == job["id"]].iloc[0]
        assert row["max_force_dyn"] == max(r["curve"]["force_moving"])
        assert row["steps"] == r["steps"]


def test_the_command_runs_a_spec_file(tmp_path):
    spec = tmp_path / "spec.json"
    spec.write_text(json.dumps({**SIX, "grid": {"pattern": ["stockinette", "garter"]}}))
    r = subprocess.run([BUILD_KNITSIM, "sweep", str(spec), "--out", str(tmp_path / "o"),
                        "--workers", "2", "--quiet"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "2 jobs, 0 failed" in r.stdout
    bad = subprocess.run([BUILD_KNITSIM, "sweep", str(tmp_path / "none.json"), "--out",
                          str(tmp_path / "p")], capture_output=True, text=True)
    assert bad.returncode == 1 and "none.json" in bad.stderr
