"""The Dask batch (sketchbody.batch): `python -m sketchbody.batch` on a local two-worker cluster
over the bundled example plus deliberately broken inputs; per-sketch records, the outputs, and
no partial output left. Also the per-task atomic writer without a cluster.

Needs dask[distributed] (scripts/test-python.sh installs it into target/py-venv); without it the
cluster test prints SKIPPED, or fails when SKB_REQUIRE_DASK=1."""

import json
import os
import shutil
import stat
import struct
import subprocess
import sys
import tempfile
import time
import unittest

from sketchbody import batch

from _util import CLI, SKETCH, SKETCH_JOINTS, write_gray_png

try:
    import distributed  # noqa: F401
    HAVE_DASK = True
except ImportError:
    HAVE_DASK = False


def batch_fit():
    """A quick fit (the tests check files and modes, not the body)."""
    from sketchbody import FitOptions

    return FitOptions(samples=8, iterations=1)


def glb_json(path):
    """The JSON chunk of a binary glTF file."""
    with open(path, "rb") as f:
        data = f.read()
    length, kind = struct.unpack("<I4s", data[12:20])
    assert data[:4] == b"glTF" and kind == b"JSON", path
    return json.loads(data[20:20 + length])


def make_inputs(folder):
    """The example with its joints, a corrupt PNG and a blank page."""
    shutil.copy(SKETCH, os.path.join(folder, "sketch.png"))
    shutil.copy(SKETCH_JOINTS, os.path.join(folder, "sketch_joints.json"))
    with open(os.path.join(folder, "broken.png"), "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + b"\x00" * 40)            # header, then garbage
    write_gray_png(os.path.join(folder, "blank.png"), 96, 96, [255] * 96 * 96)
    with open(os.path.join(folder, "notes.txt"), "w") as f:      # not a sketch: ignored
        f.write("not a sketch\n")


class FindAndConvertTest(unittest.TestCase):
    def test_find_sketches(self):
        with tempfile.TemporaryDirectory() as tmp:
            make_inputs(tmp)
            jobs = batch.find_sketches(tmp)
        self.assertEqual([j.name for j in jobs], ["blank", "broken", "sketch"])
        self.assertTrue(jobs[2].joints.endswith("sketch_joints.json"))
        self.assertIsNone(jobs[0].joints)

    def test_output_folder_mode_follows_the_umask(self):
        # Not tempfile.mkdtemp's 0700: the folder a plain mkdir would make, readable by the group.
        with tempfile.TemporaryDirectory() as src, tempfile.TemporaryDirectory() as out:
            make_inputs(src)
            job = [j for j in batch.find_sketches(src) if j.name == "sketch"][0]
            old = os.umask(0o022)
            try:
                self.assertEqual(batch.current_umask(), 0o022)
                self.assertEqual(batch.default_dir_mode(), 0o755)
                rec = batch.convert_sketch(job, out, batch_fit(), preview_size=64)
                mode = stat.S_IMODE(os.stat(os.path.join(out, "sketch")).st_mode)
                files = {f: stat.S_IMODE(os.stat(os.path.join(out, "sketch", f)).st_mode)
                         for f in os.listdir(os.path.join(out, "sketch"))}
                os.umask(0o027)
                self.assertEqual(batch.default_dir_mode(), 0o750)
                staging = batch.make_staging_dir(out, "other")
                self.assertEqual(stat.S_IMODE(os.stat(staging).st_mode), 0o750)
            finally:
                os.umask(old)
        self.assertTrue(rec["ok"], rec)
        self.assertEqual(mode, 0o755, oct(mode))
        unreadable = {f: oct(m) for f, m in files.items() if not m & stat.S_IRGRP}
        self.assertEqual(unreadable, {})

    def test_cli_arguments(self):
        from sketchbody import ExportOptions, FitOptions

        job = batch.Job("a", "/s/a.png", "/s/a_joints.json")
        args = batch.cli_arguments(job, "/o/tmp", FitOptions(gender="male", height=1.8, samples=8, seed=3),
                                   ExportOptions(naming="unreal", rest_pose="t"), preview_size=64)
        self.assertEqual(args, ["run", "/s/a.png", "--out", "/o/tmp", "--quiet", "--joints", "/s/a_joints.json",
                                "--gender", "m", "--samples", "8", "--height", "1.8", "--seed", "3",
                                "--naming", "unreal", "--rest-pose", "t", "--preview-size", "64"])
        self.assertNotIn("--gender", batch.cli_arguments(job, "/o", FitOptions(gender="auto")))
        rig = ExportOptions(twist_bones=False, pose_as="rest", ik_targets=True, shape_keys=True)
        self.assertEqual(batch.cli_arguments(job, "/o", None, rig)[7:],
                         ["--twist-bones", "false", "--pose-as", "rest", "--ik-targets", "--shape-keys", "true",
                          "--preview-size", "512"])
        with self.assertRaises(ValueError):  # an option `run` is not given: said, not dropped
            batch.cli_arguments(job, "/o", FitOptions(score="paper"))

    @unittest.skipUnless(os.access(CLI, os.X_OK) or os.environ.get("SKB_REQUIRE_SHARED_DATA"),
                         f"SKIPPED: no sketchbody command at {CLI} (set SKB_CLI)")
    def test_cli_mode_writes_the_clis_textured_glb(self):
        with tempfile.TemporaryDirectory() as src, tempfile.TemporaryDirectory() as out:
            make_inputs(src)
            jobs = {j.name: j for j in batch.find_sketches(src)}
            os.makedirs(os.path.join(out, "own"))
            old = os.umask(0o022)
            try:
                rec = batch.convert_sketch(jobs["sketch"], out, batch_fit(), preview_size=64, cli=CLI)
                bad = batch.convert_sketch(jobs["broken"], out, batch_fit(), preview_size=64, cli=CLI)
                own = batch.convert_sketch(jobs["sketch"], os.path.join(out, "own"), batch_fit(), preview_size=64)
            finally:
                os.umask(old)
            folder = os.path.join(out, "sketch")
            self.assertTrue(rec["ok"], rec)
            self.assertIn(rec["gender"], ("female", "male"))
            files = sorted(os.listdir(folder))
            for name in ("body.glb", "body_texture.png", "body.mtl", "body.obj", "report.md", "result.json"):
                self.assertIn(name, files)
            self.assertFalse([f for f in files if f.startswith(".")], files)
            self.assertEqual(stat.S_IMODE(os.stat(folder).st_mode), 0o755)
            self.assertEqual({f for f in files if not os.stat(os.path.join(folder, f)).st_mode & stat.S_IRGRP}, set())
            gltf = glb_json(os.path.join(folder, "body.glb"))
            self.assertTrue(gltf.get("images") and gltf.get("textures"), sorted(gltf))
            # The package path's GLB (no texture projection in the C API yet) has none.
            self.assertTrue(own["ok"], own)
            self.assertFalse(glb_json(os.path.join(out, "own", "sketch", "body.glb")).get("images"))
            self.assertFalse(bad["ok"])
            self.assertEqual(bad["status_name"], "CliError")
            self.assertIn("broken.png", bad["message"])
            self.assertEqual(sorted(os.listdir(out)), ["own", "sketch"])

    def test_failed_task_leaves_nothing(self):
        with tempfile.TemporaryDirectory() as src, tempfile.TemporaryDirectory() as out:
            make_inputs(src)
            job = [j for j in batch.find_sketches(src) if j.name == "broken"][0]
            rec = batch.convert_sketch(job, out)
            self.assertFalse(rec["ok"])
            self.assertEqual(rec["status_name"], "SKB_ERR_DECODE")
            self.assertEqual(os.listdir(out), [])


@unittest.skipUnless(HAVE_DASK or os.environ.get("SKB_REQUIRE_DASK") == "1",
                     "SKIPPED: dask[distributed] not installed (scripts/test-python.sh installs it)")
class LocalClusterTest(unittest.TestCase):
    def test_cli_on_two_local_workers(self):
        with tempfile.TemporaryDirectory() as src, tempfile.TemporaryDirectory() as root:
            make_inputs(src)
            out = os.path.join(root, "out")
            # A stale temporary folder from a killed earlier run is cleaned up.
            os.makedirs(os.path.join(out, ".old.partial-x1"))
            t0 = time.perf_counter()
            r = subprocess.run([sys.executable, "-m", "sketchbody.batch", src, out, "--scheduler", "local",
                                "--workers", "2", "--preview-size", "256"],
                               capture_output=True, text=True, timeout=600)
            wall = time.perf_counter() - t0
            sys.stderr.write("\n" + "".join(f"  | {line}\n" for line in r.stdout.splitlines()))
            sys.stderr.write(f"  | (test wall time including cluster start-up {wall:.1f} s)\n")
            self.assertEqual(r.returncode, 1, r.stderr[-3000:])       # 1: some sketches failed
            with open(os.path.join(out, "batch.json")) as f:
                recs = {rec["name"]: rec for rec in json.load(f)["results"]}
            self.assertEqual(set(recs), {"sketch", "broken", "blank"})
            ok = recs["sketch"]
            self.assertTrue(ok["ok"], ok)
            self.assertEqual(ok["output"], os.path.join(out, "sketch"))
            self.assertEqual(recs["broken"]["status_name"], "SKB_ERR_DECODE")
            self.assertEqual(recs["broken"]["status"], 12)
            self.assertEqual(recs["blank"]["status_name"], "SKB_ERR_BLANK_IMAGE")
            for name in ("broken", "blank"):
                self.assertFalse(recs[name]["ok"])
                self.assertTrue(recs[name]["message"])
            # Only complete outputs: the converted sketch's folder and the records.
            self.assertEqual(sorted(os.listdir(out)), ["batch.json", "sketch"])
            self.assertEqual(stat.S_IMODE(os.stat(os.path.join(out, "sketch")).st_mode),
                             0o777 & ~batch.current_umask())
            files = sorted(os.listdir(os.path.join(out, "sketch")))
            self.assertEqual(files, ["body.glb", "body.obj", "body_rest.obj", "joints2d.json", "preview.png",
                                     "result.json"])
            with open(os.path.join(out, "sketch", "result.json")) as f:
                res = json.load(f)
            self.assertIn(res["gender"], ("female", "male"))
            with open(os.path.join(out, "sketch", "body.glb"), "rb") as f:
                self.assertEqual(f.read(4), b"glTF")
            for line in ("ok    sketch", "FAIL  broken: SKB_ERR_DECODE", "FAIL  blank: SKB_ERR_BLANK_IMAGE",
                         "3 sketches: 1 ok, 2 failed"):
                self.assertIn(line, r.stdout)

    def test_cli_against_a_scheduler_address_with_skip_existing(self):
        import logging

        from distributed import LocalCluster

        with tempfile.TemporaryDirectory() as src, tempfile.TemporaryDirectory() as root, \
                LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None,
                             silence_logs=logging.ERROR) as cluster:
            make_inputs(src)
            out = os.path.join(root, "out")
            os.makedirs(os.path.join(out, "sketch"))
            with open(os.path.join(out, "sketch", "kept.txt"), "w") as f:
                f.write("an earlier run's output\n")
            r = subprocess.run([sys.executable, "-m", "sketchbody.batch", src, out, "--scheduler",
                                cluster.scheduler_address, "--skip-existing", "--quiet"],
                               capture_output=True, text=True, timeout=600)
            self.assertEqual(r.returncode, 1, r.stderr[-3000:])
            self.assertIn("3 sketches: 1 ok, 2 failed", r.stdout)
            with open(os.path.join(out, "batch.json")) as f:
                recs = {rec["name"]: rec for rec in json.load(f)["results"]}
            self.assertTrue(recs["sketch"]["ok"] and recs["sketch"]["skipped"])
            self.assertEqual(os.listdir(os.path.join(out, "sketch")), ["kept.txt"])
            self.assertEqual(recs["broken"]["status_name"], "SKB_ERR_DECODE")
            self.assertEqual(sorted(os.listdir(out)), ["batch.json", "sketch"])


if __name__ == "__main__":
    unittest.main(verbosity=2)
