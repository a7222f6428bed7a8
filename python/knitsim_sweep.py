"""Sweeps: a table of knitsim jobs (relax, stretch, simulate) run on a Dask cluster.

A sweep spec (JSON, or a dict in Python) names the jobs:

    {
      "kind": "relax",                           # the jobs' kind unless a job says
      "args": {"rows": 6, "cols": 6, "max_time": 0.01},     # every job's arguments
      "grid": {"pattern": ["stockinette", "rib1x1"],         # every combination of these
               "stitch_size": [3.5, 4.5]},
      "jobs": [{"pattern": "garter"}]            # and these (each over "args")
    }

A job's arguments are the keywords of the Python function for its kind: knitsim.relax
(relax), knitsim.stretch (stretch: from "from", a .kstate, or from "pattern", relaxed
first with "rows", "cols", "bind_off", "cast_on", "in_the_round", "stitch_size", the
keywords only relax() takes (max_time, shrink, …) and those in "relax", as `knitsim stretch
PATTERN` does), and Scene.run (simulate: "scene"
and "knit" name the files load_scene reads). Paths are relative to the spec's folder.

Each job writes its own run directory, OUT/jobs/ID/run, and, once finished,
OUT/jobs/ID/result.json: its row of the sweep's table. The stretch jobs of one knit (the
same pattern and relaxation arguments, different directions or speeds) share one
relaxation, OUT/relaxed/HASH, run once before them. A restarted
sweep runs only the jobs without a result. The rows are gathered into OUT/results.csv (and
a pandas DataFrame). A job that fails is reported in its row (status "error" and the
message) and does not stop the others; it runs again when the sweep is restarted. A
worker that dies mid-job has its job run again by the scheduler (the job's run directory
is not left locked: its lock dies with the process, and the new try overwrites what the
first wrote). Nothing outside OUT is written; OUT is refused unless it is new, empty, or an
earlier sweep's (it holds sweep.json).

The jobs run on a Dask cluster: by default a local one of `workers` processes (all cores),
or the running scheduler at `scheduler` ("tcp://host:8786", started with `dask scheduler`
and `dask worker` on each machine: docs/sweeps.md), where every worker must import the
same knitsim and read the same paths.

    knitsim sweep SPEC --out OUT [--workers N] [--scheduler ADDRESS]   (run_command)
    knitsim.sweep(spec, "OUT")  ->  pandas.DataFrame
"""

import hashlib
import itertools
import json
import os
import re
import sys
import time

FORMAT = "knitsim-sweep-1"
MARKER = "sweep.json"
RESULT = "result.json"
KINDS = ("relax", "stretch", "simulate")
# the keywords of a stretch job from a pattern that go to its relaxation
RELAX_KEYS_OF_STRETCH = ("pattern", "rows", "cols", "bind_off", "cast_on", "in_the_round",
                         "stitch_size")
# the keys that name files (read relative to the spec's folder)
PATH_KEYS = ("pattern", "from", "scene", "knit")


class SpecError(ValueError):
    """A sweep spec that cannot be run; the message names the spec and what is wrong."""


def _write_atomic(path, text):
    tmp = path + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(text)
    os.replace(tmp, path)


def load_spec(spec):
    """The spec as a dict, and the folder its paths are relative to (a path's, else the
    working directory)."""
    if isinstance(spec, dict):
        return spec, os.getcwd(), "the spec"
    path = os.fspath(spec)
    try:
        with open(path, encoding="utf-8") as f:
            data = json.load(f)
    except FileNotFoundError:
        raise FileNotFoundError(f"sweep spec {path}: no such file") from None
    except json.JSONDecodeError as e:
        raise SpecError(f"sweep spec {path}: not JSON: {e}") from None
    return data, os.path.dirname(os.path.abspath(path)), path


def _resolve_paths(args, base):
    out = dict(args)
    for key in PATH_KEYS:
        value = out.get(key)
        if isinstance(value, str) and value and not os.path.isabs(value):
            candidate = os.path.join(base, value)
            # a pattern may be a built-in name: only an existing file is a path
            if key != "pattern" or os.path.exists(candidate):
                out[key] = candidate
    if isinstance(out.get("relax"), dict):
        out["relax"] = _resolve_paths(out["relax"], base)
    return out


def _label(kind, vary):
    text = "-".join(f"{k}={os.path.basename(str(v))}" for k, v in vary.items()) or kind
    return re.sub(r"[^A-Za-z0-9=._+-]", "_", f"{kind}-{text}")[:80]


def expand(spec):
    """The spec's jobs, in order: each a dict with its id (a label of what varies and a hash
    of the kind and arguments, so that the same job has the same id in every sweep), kind,
    arguments and the values that vary. Raises SpecError naming what is wrong."""
    return _expand(*load_spec(spec))


def _expand(data, base, name):
    if not isinstance(data, dict):
        raise SpecError(f"{name}: a sweep spec is a JSON object")
    unknown = set(data) - {"kind", "args", "grid", "jobs", "name"}
    if unknown:
        raise SpecError(f"{name}: unknown keys {sorted(unknown)} (kind, args, grid, jobs, name)")
    kind = data.get("kind", "relax")
    common = data.get("args", {})
    grid = data.get("grid", {})
    listed = data.get("jobs", [])
    if not isinstance(common, dict):
        raise SpecError(f"{name}: args is an object of keyword arguments")
    if not isinstance(grid, dict) or not all(isinstance(v, list) and v for v in grid.values()):
        raise SpecError(f"{name}: grid is an object of non-empty lists")
    if not isinstance(listed, list) or not all(isinstance(j, dict) for j in listed):
        raise SpecError(f"{name}: jobs is a list of objects")
    varied = []
    if grid:
        keys = list(grid)
        for values in itertools.product(*(grid[k] for k in keys)):
            varied.append(dict(zip(keys, values)))
    varied += listed
    if not varied:
        varied = [{}]
    jobs, seen = [], set()
    for k, vary in enumerate(varied):
        vary = dict(vary)
        job_kind = vary.pop("kind", kind)
        if job_kind not in KINDS:
            raise SpecError(f"{name}: job {k}: kind {job_kind!r} is not one of {', '.join(KINDS)}")
        args = _resolve_paths({**common, **vary}, base)
        for reserved in ("out", "overwrite", "progress", "threads"):
            if reserved in args:
                raise SpecError(f"{name}: job {k}: {reserved!r} is the sweep's to set")
        canonical = json.dumps({"kind": job_kind, "args": args}, sort_keys=True)
        digest = hashlib.sha256(canonical.encode()).hexdigest()[:10]
        job_id = f"{_label(job_kind, vary)}-{digest}"
        if job_id in seen:
            continue  # the same job listed twice runs once
        seen.add(job_id)
        job = {"id": job_id, "kind": job_kind, "args": args, "vary": vary}
        if job_kind == "stretch" and "from" not in args:
            _split_relaxation(job)
        jobs.append(job)
    return jobs


def _split_relaxation(job):
    """A stretch job from a pattern: its relaxation's arguments (the knit's own, those
    relax() takes and stretch() does not, and "relax") go to job["relax"], named by a hash
    of them, so that the stretch jobs of one knit share one relaxation."""
    import knitsim

    args = dict(job["args"])
    relax_args = dict(args.pop("relax", {}))
    only_relax = _keywords(knitsim.relax) - _keywords(knitsim.stretch)
    for key in list(args):
        if key in RELAX_KEYS_OF_STRETCH or key in only_relax:
            relax_args[key] = args.pop(key)
    canonical = json.dumps(relax_args, sort_keys=True)
    job["args"] = args
    job["relax"] = {"id": hashlib.sha256(canonical.encode()).hexdigest()[:12],
                    "args": relax_args}


def _job_dir(out, job):
    return os.path.join(out, "jobs", job["id"])


def _summary_row(summary, prefix=""):
    keys = ("status", "steps", "sim_time_s", "wall_time_s", "relaxed", "course_extent_cm",
            "wale_extent_cm", "loop_length_cm", "edge_curl", "min_contact_distance")
    row = {prefix + k: summary[k] for k in keys if k in summary}
    if isinstance(summary.get("crossings"), dict):
        row[prefix + "crossings"] = summary["crossings"].get("count")
    return row


def run_relaxation(relax, out, threads=1):
    """The relaxation stretch jobs of one knit share: into OUT/relaxed/ID/run, its outcome
    (the relaxed state's path, its row's relax_ columns, or the error) written to
    OUT/relaxed/ID/result.json when it finished. A relaxation already finished returns its
    recorded outcome. Runs in a Dask worker, or here."""
    import knitsim

    d = os.path.join(out, "relaxed", relax["id"])
    done = os.path.join(d, RESULT)
    if os.path.exists(done):
        with open(done, encoding="utf-8") as f:
            return json.load(f)
    os.makedirs(d, exist_ok=True)
    run_dir = os.path.join(d, "run")
    outcome = {"kstate": os.path.join(run_dir, "final.kstate"), "row": {}, "error": None}
    try:
        if "pattern" not in relax["args"]:
            raise ValueError("a stretch job needs 'from' (a .kstate) or 'pattern'")
        k = knitsim.relax(**relax["args"], out=run_dir, overwrite=True, threads=threads,
                          frames=False)
        outcome["row"] = _summary_row(k.summary, "relax_")
        if k.status != "ok":
            outcome["error"] = f"the relaxation ended {k.status}: {k.summary.get('message', '')}"
    except Exception as e:
        outcome["error"] = f"the relaxation failed: {type(e).__name__}: {e}"
        return outcome  # (not recorded: a restart tries it again)
    _write_atomic(done, json.dumps(outcome, indent=1))
    return outcome


def run_job(job, out, threads=1, relaxed=None):
    """Runs one job into OUT/jobs/ID and returns its row (written to its result.json).
    A job already finished returns its recorded row. A stretch job from a pattern takes its
    relaxation's outcome (run_relaxation), or runs it. Runs in a Dask worker, or here."""
    import knitsim

    d = _job_dir(out, job)
    done = os.path.join(d, RESULT)
    if os.path.exists(done):
        with open(done, encoding="utf-8") as f:
            return json.load(f)
    os.makedirs(d, exist_ok=True)
    row = {"id": job["id"], "kind": job["kind"], **{k: _cell(v) for k, v in job["vary"].items()}}
    args = dict(job["args"])
    run_dir = os.path.join(d, "run")
    started = time.time()
    try:
        if job["kind"] == "relax":
            k = knitsim.relax(**args, out=run_dir, overwrite=True, threads=threads)
            row.update(_summary_row(k.summary))
        elif job["kind"] == "stretch":
            kstate = args.pop("from", None)
            if "relax" in job:  # from a pattern, relaxed first
                if relaxed is None:
                    relaxed = run_relaxation(job["relax"], out, threads)
                row.update(relaxed["row"])
                if relaxed["error"]:
                    raise RuntimeError(relaxed["error"])
                kstate = relaxed["kstate"]
            r = knitsim.stretch(kstate, **args, out=run_dir, overwrite=True, threads=threads)
            row.update(_summary_row({**r["summary"], "status": r["status"], "steps": r["steps"]}))
            curve = r["curve"]
            if len(curve["strain"]):
                row["max_strain"] = float(max(curve["strain"]))
                row["max_force_dyn"] = float(max(curve["force_moving"]))
                row["force_at_end_dyn"] = float(curve["force_moving"][-1])
        else:
            scene = knitsim.load_scene(args.pop("scene"), **({"knit": args.pop("knit")}
                                                              if "knit" in args else {}))
            report = scene.run(**args, out=run_dir, overwrite=True, threads=threads)
            row.update(_summary_row({**report["summary"], "status": report["status"],
                                     "steps": report["steps"]}))
    except Exception as e:  # the job's own error, in its row; the others go on
        row.update({"status": "error", "error": f"{type(e).__name__}: {e}"})
        row["job_seconds"] = round(time.time() - started, 3)
        return row
    row["job_seconds"] = round(time.time() - started, 3)
    _write_atomic(done, json.dumps(row, indent=1))
    return row


def _keywords(function):
    """The named arguments of a module function, from its signature line."""
    return set(re.findall(r"(\w+): ", function.__doc__.splitlines()[0]))


def _cell(v):
    return v if isinstance(v, (int, float, str, bool)) or v is None else json.dumps(v)


def _prepare(out, jobs, spec_text):
    if os.path.exists(out) and not os.path.isdir(out):
        raise SpecError(f"{out}: not a directory")
    if os.path.isdir(out) and os.listdir(out) and not os.path.exists(os.path.join(out, MARKER)):
        raise SpecError(f"{out}: holds files and is not a sweep's (no {MARKER}); give a new or "
                        "empty directory, or an earlier sweep's to go on with it")
    os.makedirs(os.path.join(out, "jobs"), exist_ok=True)
    _write_atomic(os.path.join(out, MARKER),
                  json.dumps({"format": FORMAT, "spec": spec_text,
                              "jobs": [j["id"] for j in jobs]}, indent=1))


def sweep(spec, out, scheduler=None, workers=None, threads=1, progress=False):
    """Runs the spec's jobs (a path or a dict) into `out` on a Dask cluster and returns the
    table as a pandas DataFrame (also written to OUT/results.csv), one row per job in the
    spec's order. `scheduler`: a running scheduler's address (default: a local cluster of
    `workers` processes, default all cores); `threads`: each job's threads (default 1)."""
    import pandas as pd

    data, base, name = load_spec(spec)
    jobs = _expand(data, base, name)
    out = os.path.abspath(os.fspath(out))
    _prepare(out, jobs, data)
    rows = {}
    pending = []
    for j in jobs:
        done = os.path.join(_job_dir(out, j), RESULT)
        if os.path.exists(done):
            with open(done, encoding="utf-8") as f:
                rows[j["id"]] = json.load(f)
        else:
            pending.append(j)
    if pending:
        rows.update(_run_on_cluster(pending, out, scheduler, workers, threads, progress))
    table = pd.DataFrame([rows[j["id"]] for j in jobs])
    _write_atomic(os.path.join(out, "results.csv"), table.to_csv(index=False))
    _plot_stretch_curves(out, jobs, rows)
    return table


def _knitsim_program():
    """The knitsim program beside the module (a build's), else on the PATH, else None."""
    import shutil

    import knitsim

    beside = os.path.join(os.path.dirname(os.path.abspath(knitsim.__file__)), "..", "knitsim")
    return beside if os.access(beside, os.X_OK) else shutil.which("knitsim")


def _plot_stretch_curves(out, jobs, rows):
    """The finished stretch jobs' force–strain curves, one plot per direction:
    OUT/plots/stretch_DIRECTION.csv (the force on the moving clamp, dyn, of each job at the
    strains 0, 0.01, … up to the least strain they all reached, linearly interpolated) and
    .png (drawn by `knitsim plot`)."""
    import numpy as np

    by_direction = {}
    for j in jobs:
        curve = os.path.join(_job_dir(out, j), "run", "stretch.csv")
        if j["kind"] != "stretch" or rows[j["id"]].get("status") == "error" or \
                not os.path.exists(curve):
            continue
        data = np.genfromtxt(curve, delimiter=",", names=True)
        if data.size < 2:
            continue
        direction = str(j["args"].get("direction", "course"))
        name = " ".join(f"{v}" for k, v in j["vary"].items() if k != "direction") or j["id"]
        by_direction.setdefault(direction, []).append((name, data["strain"],
                                                       data["force_moving_dyn"]))
    if not by_direction:
        return
    os.makedirs(os.path.join(out, "plots"), exist_ok=True)
    program = _knitsim_program()
    for direction, curves in by_direction.items():
        # up to the strain every curve reached
        top = min(float(c[1].max()) for c in curves)
        grid = np.arange(0, top + 1e-6, 0.01)
        lines = ["strain," + ",".join(f"{n} force (dyn)".replace(",", " ") for n, _, _ in curves)]
        for x in grid:
            lines.append(f"{x:.4g}," + ",".join(f"{np.interp(x, s, f):.6g}" for _, s, f in curves))
        csv = os.path.join(out, "plots", f"stretch_{direction}.csv")
        _write_atomic(csv, "\n".join(lines) + "\n")
        if program:
            import subprocess

            subprocess.run([program, "plot", csv, "--out", csv[:-4] + ".png"],
                           capture_output=True, check=False)


class _LocalCluster:
    """A scheduler in this process and `n` workers as `dask worker` processes (each a nanny
    that starts a new worker when its worker dies), on this machine's loopback. Workers run
    in fresh interpreters: a user's script that calls sweep() is not imported again by them
    (as multiprocessing's spawn would), so it needs no `if __name__ == "__main__"` guard.
    Their scratch space is `scratch` (OUT/.dask), not the system's temporary folder."""

    def __init__(self, n, scratch):
        import logging
        import subprocess

        from distributed import LocalCluster

        self.cluster = LocalCluster(n_workers=0, processes=False, protocol="tcp://",
                                    host="127.0.0.1", dashboard_address=None,
                                    silence_logs=logging.ERROR)
        self.address = self.cluster.scheduler_address
        self.workers = [subprocess.Popen(
            [sys.executable, "-m", "distributed.cli.dask_worker", self.address,
             "--nworkers", "1", "--nthreads", "1", "--no-dashboard", "--host", "127.0.0.1",
             "--name", f"knitsim-sweep-{k}", "--local-directory", scratch],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL) for k in range(n)]

    def close(self):
        import signal
        import subprocess

        for w in self.workers:
            if w.poll() is None:
                w.send_signal(signal.SIGTERM)
        for w in self.workers:
            try:
                w.wait(timeout=20)
            except subprocess.TimeoutExpired:
                w.kill()
                w.wait()
        self.cluster.close()


def _run_on_cluster(jobs, out, scheduler, workers, threads, progress):
    from distributed import Client, as_completed

    local = None
    if scheduler:
        client = Client(scheduler)
    else:
        n = workers or os.cpu_count() or 1
        local = _LocalCluster(n, os.path.join(out, ".dask"))
        client = Client(local.address)
        client.wait_for_workers(n, timeout=120)
    try:
        # the relaxations the stretch jobs share first, each once; a stretch job waits for its
        relaxations = {}
        for j in jobs:
            if "relax" in j and j["relax"]["id"] not in relaxations:
                relaxations[j["relax"]["id"]] = client.submit(
                    run_relaxation, j["relax"], out, threads,
                    key=f"knitsim-relax-{j['relax']['id']}", pure=False)
        futures = {client.submit(run_job, j, out, threads,
                                 relaxations[j["relax"]["id"]] if "relax" in j else None,
                                 key=f"knitsim-job-{j['id']}", pure=False): j["id"] for j in jobs}
        bar = None
        if progress:
            from tqdm import tqdm
            bar = tqdm(total=len(jobs), unit="job", desc="sweep", file=sys.stderr)
        rows = {}
        for future in as_completed(futures):
            rows[futures[future]] = future.result()
            if bar:
                bar.update(1)
        if bar:
            bar.close()
        return rows
    finally:
        client.close()
        if local is not None:
            local.close()


def run_command(options):
    """`knitsim sweep` (apps/knitsim/cmd_sweep.cpp, which declares and checks the options and
    passes them here as JSON): runs the sweep, prints the count and the failed jobs, and
    returns the exit code (0; 1 when a job failed or the spec was refused)."""
    o = json.loads(options)
    try:
        table = sweep(o["spec"], o["out"], scheduler=o["scheduler"] or None,
                      workers=o["workers"] or None, threads=o["threads"],
                      progress=o["progress"])
    except (SpecError, FileNotFoundError) as e:
        print(f"knitsim: error: sweep: {e}", file=sys.stderr)
        return 1
    errors = table[table["status"] == "error"] if "status" in table else table.iloc[0:0]
    print(f"{len(table)} jobs, {len(errors)} failed; table: {os.path.join(o['out'], 'results.csv')}")
    for _, r in errors.iterrows():
        print(f"  {r['id']}: {r.get('error', '')}", file=sys.stderr)
    return 1 if len(errors) else 0
