"""Batch conversion of a folder of sketches on a Dask distributed cluster.

    python -m sketchbody.batch SKETCH_DIR OUT_DIR [--scheduler local|tcp://HOST:8786] [--workers 2]

One task per sketch. A sketch `NAME.png` (or .jpg/.jpeg) uses the 2-D joints in
`NAME_joints.json` or `NAME.joints.json` beside it when present (the paper's user-correction
step), else the embedded detector. Each task writes `OUT_DIR/NAME/` (body.glb, body.obj,
body_rest.obj, joints2d.json, result.json, preview.png) atomically: into a hidden temporary
folder `OUT_DIR/.NAME.partial-*` first, renamed to `OUT_DIR/NAME` when complete, so a failed or
killed task never leaves a half-written `NAME/`. A failure is reported per sketch (a record
with the status name and message) and never stops the batch. The records are printed as the
tasks finish and written to `OUT_DIR/batch.json`; the exit status is 0 when every sketch
converted, 1 when some failed.

With `--cli PATH` each task runs that `sketchbody` command's `run` instead of the package (the
command must be at PATH on every worker): the outputs are the CLI's (body.glb with the sketch
projected as its texture, body_texture.png, body.mtl, pose3d.json, overlay.png, report.md, ...)
plus result.json, written the same atomic way. The package path's body.glb has no texture: the C
API has no texture projection yet.

With `--scheduler local` (the default) a LocalCluster of `--workers` processes is started
in-process; with an address the tasks go to a running cluster (`dask scheduler`, `dask worker`
on each machine, sketchbody installed on each, SKETCH_DIR and OUT_DIR on storage every worker
sees at the same path; docs/python.md). `sketchbody-lab run-dataset` stays the single-machine path.

Why Dask distributed rather than Ray: dask and distributed are pure-Python packages that pip
installs on the Python the package already uses, a LocalCluster runs in-process
for the tests and for one workstation, the same code talks to a multi-machine cluster through
one scheduler address, and its futures API (submit, as_completed, per-future exceptions) is all
a one-task-per-file batch needs. Ray brings a large binary runtime (its own object store and
control service) that this coarse, file-in/file-out workload does not use.
"""

import argparse
import dataclasses
import glob
import json
import logging
import os
import re
import shutil
import socket
import sys
import tempfile
import time
import uuid

SKETCH_EXTENSIONS = (".png", ".jpg", ".jpeg")
RESULTS_FILE = "batch.json"


@dataclasses.dataclass
class Job:
    """One sketch to convert: `name` (the output folder's name), `sketch` and the optional
    `joints` file (absolute paths)."""

    name: str
    sketch: str
    joints: str = None


def find_sketches(sketch_dir):
    """The Jobs of the PNG/JPEG files in `sketch_dir` (not recursive), sorted by name."""
    jobs, seen = [], set()
    for path in sorted(glob.glob(os.path.join(glob.escape(os.path.abspath(sketch_dir)), "*"))):
        stem, ext = os.path.splitext(os.path.basename(path))
        if ext.lower() not in SKETCH_EXTENSIONS or not os.path.isfile(path) or stem.startswith("."):
            continue
        name = stem if stem not in seen else f"{stem}_{ext[1:].lower()}"
        seen.add(name)
        joints = None
        for cand in (f"{stem}_joints.json", f"{stem}.joints.json"):
            p = os.path.join(os.path.dirname(path), cand)
            if os.path.isfile(p):
                joints = p
                break
        jobs.append(Job(name, path, joints))
    return jobs


def _record(job, **kw):
    rec = {"name": job.name, "sketch": job.sketch, "joints": job.joints, "ok": False, "skipped": False,
           "status": None, "status_name": None, "message": "", "output": None, "seconds": 0.0,
           "host": socket.gethostname(), "pid": os.getpid()}
    rec.update(kw)
    return rec


def current_umask():
    """The process's file-mode creation mask, read without changing it where Linux shows it
    (/proc/self/status), else by setting and restoring it."""
    try:
        with open("/proc/self/status", encoding="ascii") as f:
            for line in f:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def default_dir_mode():
    """The mode `mkdir` gives a new folder: 0o777 less the umask (0o755 with the usual 022;
    group-readable, unlike tempfile.mkdtemp's 0o700)."""
    return 0o777 & ~current_umask()


def make_staging_dir(out_dir, name):
    """A new hidden folder `out_dir/.NAME.partial-*` for one task's outputs, with the mode a
    plain mkdir would give (default_dir_mode()), so the folder renamed into place is as
    readable by the group as any other folder the user makes."""
    tmp = tempfile.mkdtemp(prefix=f".{name}.partial-", dir=out_dir)
    os.chmod(tmp, default_dir_mode())
    return tmp


def _write_json(path, data):
    with open(path, "w", encoding="utf-8") as f:
        json.dump(data, f, indent=2)
        f.write("\n")


def _write_with_package(job, tmp, fit_options, export_options, preview_size):
    """Writes one sketch's outputs into the folder `tmp` through the Python package; returns the
    result.json summary (without its seconds)."""
    import sketchbody as skb  # imported on the worker

    with skb.run_pipeline(job.sketch, joints=job.joints, fit_options=fit_options) as result, \
            result.mesh() as mesh:
        mesh.write_glb(os.path.join(tmp, "body.glb"), export_options)
        mesh.write_obj(os.path.join(tmp, "body.obj"), posed=True)
        mesh.write_obj(os.path.join(tmp, "body_rest.obj"), posed=False)
        if preview_size:
            mesh.write_preview(os.path.join(tmp, "preview.png"), preview_size)
        result.joints2d().to_json(os.path.join(tmp, "joints2d.json"))
        cam = result.camera()
        low, support = result.evidence()
        value, confidence = result.gender_value()
        return {
            "format": "sketchbody-batch-result", "version": 1, "sketch": job.sketch, "joints": job.joints,
            "writer": "package", "gender": result.gender, "gender_fitted": result.gender_fitted,
            "gender_value": value, "gender_confidence": confidence, "score": result.score, "low_evidence": low,
            "edge_support": support, "library_version": skb.version(),
            "camera": {"sx": cam.sx, "sy": cam.sy, "r": cam.r.tolist(), "t": cam.t.tolist()},
            "joints3d_posed": result.joints3d("posed").tolist(),
            "shape_weights": result.shape_weights().tolist(),
        }


class CliFailed(Exception):
    """`sketchbody run` failed on a sketch: `status` its exit status, `message` its error text."""

    status_name = "CliError"

    def __init__(self, status, message):
        super().__init__(message)
        self.status, self.message = status, message


_CLI_FIT = {"height": "--height", "samples": "--samples", "iterations": "--iterations", "seed": "--seed"}
_CLI_EXPORT = {"naming": "--naming", "rest_pose": "--rest-pose", "origin": "--origin",
               "twist_bones": "--twist-bones", "pose_as": "--pose-as", "ik_targets": "--ik-targets",
               "shape_keys": "--shape-keys"}
# Options the CLI takes as a bare flag (present: on).
_CLI_SWITCHES = {"ik_targets"}
_CLI_GENDER = {"female": "f", "f": "f", "male": "m", "m": "m", "auto": None}


def _option_arguments(options, flags, what):
    """The CLI flags of the options' set fields (`flags`: field -> flag); ValueError for a set
    field the batch's CLI mode does not pass on."""
    args = []
    for field in dataclasses.fields(options) if options is not None else ():
        value = getattr(options, field.name)
        if value is None or field.name == "gender":
            continue
        if field.name not in flags:
            raise ValueError(f"{what}.{field.name} is not passed to `sketchbody run` by the batch's --cli mode")
        if field.name in _CLI_SWITCHES:
            args += [flags[field.name]] if value else []
        elif isinstance(value, bool):
            args += [flags[field.name], str(value).lower()]
        else:
            args += [flags[field.name], str(value)]
    return args


def cli_arguments(job, out, fit_options=None, export_options=None, preview_size=512):
    """The `sketchbody run` arguments that convert `job` into the folder `out` with the options
    the package path would use (gender, height, samples, iterations, seed; naming, rest pose,
    origin, twist bones, pose as, IK targets, shape keys; the preview's size)."""
    args = ["run", job.sketch, "--out", out, "--quiet"]
    if job.joints:
        args += ["--joints", job.joints]
    gender = getattr(fit_options, "gender", None)
    if gender is not None:
        if str(gender).lower() not in _CLI_GENDER:
            raise ValueError(f"gender {gender!r}: expected female, male or auto")
        if _CLI_GENDER[str(gender).lower()]:
            args += ["--gender", _CLI_GENDER[str(gender).lower()]]
    args += _option_arguments(fit_options, _CLI_FIT, "FitOptions")
    args += _option_arguments(export_options, _CLI_EXPORT, "ExportOptions")
    if preview_size:
        args += ["--preview-size", str(preview_size)]
    return args


def _write_with_cli(cli, job, tmp, fit_options, export_options, preview_size):
    """Writes one sketch's outputs into the folder `tmp` with the command-line tool `cli`
    (`sketchbody run`: its files, body.glb with the sketch as texture); returns the result.json
    summary (gender and height from its report line). CliFailed when it fails."""
    import subprocess

    r = subprocess.run([cli] + cli_arguments(job, tmp, fit_options, export_options, preview_size),
                       capture_output=True, text=True)
    if r.returncode != 0:
        lines = [line.strip() for line in r.stderr.splitlines() if line.strip()]
        raise CliFailed(r.returncode, lines[-1] if lines else f"exit status {r.returncode}")
    m = re.search(r"\b(female|male)\b.*?([\d.]+) m tall", r.stdout)
    return {"format": "sketchbody-batch-result", "version": 1, "sketch": job.sketch, "joints": job.joints,
            "writer": "cli", "cli": cli, "cli_report": r.stdout.strip(), "gender": m.group(1) if m else None,
            "height": float(m.group(2)) if m else None}


def _replace(final, tmp, out_dir, name):
    """Moves the complete folder `tmp` to `final`, replacing an earlier one (moved aside first,
    removed after)."""
    old = None
    if os.path.lexists(final):
        old = tempfile.mkdtemp(prefix=f".{name}.old-", dir=out_dir)
        os.rename(final, os.path.join(old, name))
    os.rename(tmp, final)
    if old:
        shutil.rmtree(old, ignore_errors=True)


def convert_sketch(job, out_dir, fit_options=None, export_options=None, skip_existing=False, preview_size=512,
                   cli=None):
    """Converts one sketch into `out_dir/job.name/` atomically (runs on a worker): through the
    Python package, or with `cli` (the path of the `sketchbody` command) its `run`, whose
    body.glb carries the sketch as texture. Returns a record dict: ok, status / status_name /
    message on failure, output, seconds, host, pid. Never raises for a bad sketch: every
    exception becomes a failed record."""
    t0 = time.perf_counter()
    final = os.path.join(out_dir, job.name)
    if skip_existing and os.path.isdir(final):
        return _record(job, ok=True, skipped=True, output=final)
    tmp = None
    try:
        tmp = make_staging_dir(out_dir, job.name)
        if cli:
            summary = _write_with_cli(cli, job, tmp, fit_options, export_options, preview_size)
        else:
            summary = _write_with_package(job, tmp, fit_options, export_options, preview_size)
        summary["seconds"] = time.perf_counter() - t0
        _write_json(os.path.join(tmp, "result.json"), summary)
        _replace(final, tmp, out_dir, job.name)
        tmp = None
        return _record(job, ok=True, output=final, seconds=time.perf_counter() - t0, gender=summary["gender"],
                       score=summary.get("score"))
    except Exception as e:  # noqa: BLE001 - reported per sketch
        status = getattr(e, "status", None)
        name = getattr(e, "status_name", None) or type(e).__name__
        return _record(job, status=status, status_name=name, message=getattr(e, "message", None) or str(e),
                       seconds=time.perf_counter() - t0)
    finally:
        if tmp:
            shutil.rmtree(tmp, ignore_errors=True)


def clean_stale(out_dir):
    """Removes the hidden temporary folders a killed task may have left in `out_dir`."""
    removed = []
    for pattern in (".*.partial-*", ".*.old-*"):
        for p in glob.glob(os.path.join(glob.escape(out_dir), pattern)):
            shutil.rmtree(p, ignore_errors=True)
            removed.append(p)
    return removed


def start_client(scheduler="local", workers=2, threads_per_worker=1, rayon_threads=None):
    """A dask.distributed Client: a LocalCluster of `workers` processes for "local", else
    the scheduler at `scheduler` (e.g. "tcp://10.0.0.5:8786"). `rayon_threads` sets
    RAYON_NUM_THREADS in the local workers (default: the cores divided among the workers)."""
    from distributed import Client, LocalCluster

    if scheduler in (None, "", "local"):
        if rayon_threads is None:
            rayon_threads = max(1, (os.cpu_count() or 1) // max(1, workers * threads_per_worker))
        cluster = LocalCluster(n_workers=workers, threads_per_worker=threads_per_worker, processes=True,
                               dashboard_address=None, silence_logs=logging.ERROR,
                               env={"RAYON_NUM_THREADS": str(rayon_threads)})
        return Client(cluster)
    return Client(scheduler)


def run_batch(sketch_dir, out_dir, client=None, scheduler="local", workers=2, threads_per_worker=1,
              rayon_threads=None, fit_options=None, export_options=None, skip_existing=False, preview_size=512,
              on_result=None, cli=None):
    """Converts every sketch of `sketch_dir` into `out_dir`, one Dask task per sketch, on
    `client` (None: start_client(scheduler, workers, ...), closed at the end). Calls
    `on_result(record)` as each task finishes; writes all records to `out_dir/batch.json`;
    returns them sorted by name. A task whose worker dies is reported with status_name
    "WorkerError" (Dask reschedules it first, up to its allowed-failures). `cli`: the path of the
    `sketchbody` command on the workers, to convert with its `run` (textured body.glb) instead
    of the package."""
    from distributed import as_completed

    out_dir = os.path.abspath(out_dir)
    os.makedirs(out_dir, exist_ok=True)
    clean_stale(out_dir)
    jobs = find_sketches(sketch_dir)
    own = client is None
    if own:
        client = start_client(scheduler, workers, threads_per_worker, rayon_threads)
    records = []
    try:
        futures = {}
        for job in jobs:
            fut = client.submit(convert_sketch, job, out_dir, fit_options, export_options, skip_existing, preview_size,
                                cli, key=f"sketchbody-{job.name}-{uuid.uuid4().hex[:8]}", pure=False)
            futures[fut] = job
        for fut in as_completed(list(futures)):
            job = futures[fut]
            try:
                rec = fut.result()
            except Exception as e:  # noqa: BLE001 - the worker died or the task could not run
                rec = _record(job, status_name="WorkerError", message=f"{type(e).__name__}: {e}")
            records.append(rec)
            if on_result:
                on_result(rec)
    finally:
        if own:
            cluster = getattr(client, "cluster", None)
            client.close()
            if cluster is not None:
                cluster.close()
    records.sort(key=lambda r: r["name"])
    tmp = os.path.join(out_dir, f".{RESULTS_FILE}.tmp-{os.getpid()}")
    _write_json(tmp, {"format": "sketchbody-batch", "version": 1, "sketch_dir": os.path.abspath(sketch_dir),
                      "results": records})
    os.replace(tmp, os.path.join(out_dir, RESULTS_FILE))
    return records


def _line(rec):
    if rec["ok"]:
        score = f", score {rec['score']:.3f}" if rec.get("score") is not None else ""
        what = "skipped (exists)" if rec["skipped"] else f"{rec.get('gender', '')}{score}"
        return f"ok    {rec['name']}: {rec['seconds']:.1f} s, {what} -> {rec['output']}"
    return f"FAIL  {rec['name']}: {rec['status_name']}: {rec['message']} ({rec['seconds']:.1f} s)"


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m sketchbody.batch",
                                 description="Convert a folder of sketches on a Dask cluster, one task per sketch.")
    ap.add_argument("sketch_dir", metavar="SKETCH_DIR")
    ap.add_argument("out_dir", metavar="OUT_DIR")
    ap.add_argument("--scheduler", default="local", help="'local' (a LocalCluster in-process) or ADDRESS "
                    "of a running scheduler (tcp://host:8786)")
    ap.add_argument("--workers", type=int, default=2, help="local worker processes (default 2)")
    ap.add_argument("--threads-per-worker", type=int, default=1, help="tasks per local worker at once (default 1)")
    ap.add_argument("--rayon-threads", type=int, default=None,
                    help="the library's threads per local worker (default: cores / workers)")
    ap.add_argument("--gender", choices=["f", "m", "auto"], default=None)
    ap.add_argument("--height", type=float, default=None, help="the characters' rest height, metres")
    ap.add_argument("--samples", type=int, default=None)
    ap.add_argument("--iterations", type=int, default=None)
    ap.add_argument("--seed", type=int, default=None)
    ap.add_argument("--naming", choices=["project", "mixamo", "unreal"], default=None)
    ap.add_argument("--rest-pose", choices=["a", "t"], default=None)
    ap.add_argument("--origin", choices=["floor", "pelvis"], default=None)
    ap.add_argument("--preview-size", type=int, default=512, help="preview.png size; 0: no preview")
    ap.add_argument("--skip-existing", action="store_true", help="keep OUT_DIR/NAME folders already there")
    ap.add_argument("--cli", metavar="PATH", default=None,
                    help="convert with this `sketchbody` command's `run` (on every worker) instead of the package: "
                         "its outputs, body.glb with the sketch as texture")
    ap.add_argument("--quiet", action="store_true")
    a = ap.parse_args(argv)
    if a.workers < 1 or a.threads_per_worker < 1:
        ap.error("--workers and --threads-per-worker must be >= 1")
    if not os.path.isdir(a.sketch_dir):
        ap.error(f"{a.sketch_dir}: not a folder")

    from .mesh import ExportOptions
    from .pipeline import FitOptions

    fit = FitOptions(gender=a.gender, height=a.height, samples=a.samples, iterations=a.iterations, seed=a.seed)
    export = ExportOptions(naming=a.naming, rest_pose=a.rest_pose, origin=a.origin)
    t0 = time.perf_counter()
    show = None if a.quiet else (lambda r: print(_line(r), flush=True))
    records = run_batch(a.sketch_dir, a.out_dir, scheduler=a.scheduler, workers=a.workers,
                        threads_per_worker=a.threads_per_worker, rayon_threads=a.rayon_threads, fit_options=fit,
                        export_options=export, skip_existing=a.skip_existing, preview_size=a.preview_size,
                        on_result=show, cli=a.cli)
    ok = sum(r["ok"] for r in records)
    print(f"{len(records)} sketches: {ok} ok, {len(records) - ok} failed; wall {time.perf_counter() - t0:.1f} s; "
          f"results in {os.path.join(os.path.abspath(a.out_dir), RESULTS_FILE)}")
    return 0 if ok == len(records) else 1


if __name__ == "__main__":
    sys.exit(main())
