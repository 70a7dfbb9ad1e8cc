"""The driver on a local Ray cluster with the real trgs: the built-in scene split in two blocks,
each trained as a Ray task; one block's `trgs train` and the other's Ray worker are killed
after their first checkpoint; both blocks resume, finish with every step logged once, and merge
into one model; a second run keeps the finished blocks.

Needs Ray (pip install python/trgs_ray) and the trgs binary in TRGS_BIN (scripts/test.sh sets
both); skipped without them unless TRGS_RAY_REQUIRED=1.
"""

import json
import os
import signal
import subprocess
import sys
import tempfile
import time
import unittest
from pathlib import Path

TRGS = os.environ.get("TRGS_BIN", "")
REQUIRED = os.environ.get("TRGS_RAY_REQUIRED") == "1"
STEPS = 40

try:
    import ray  # noqa: F401

    HAVE_RAY = True
except ImportError:
    HAVE_RAY = False


def trgs(*args, cwd=None):
    done = subprocess.run([TRGS, *map(str, args)], check=False, capture_output=True, text=True, cwd=cwd)
    if done.returncode != 0:
        raise AssertionError(f"trgs {' '.join(map(str, args))} failed:\n{done.stdout}\n{done.stderr}")
    return done.stdout


def train_processes(run_dir: Path) -> list:
    """(pid, parent pid) of each `trgs train` writing to `run_dir`."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            argv = (entry / "cmdline").read_bytes().split(b"\0")
            fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if b"train" in argv and str(run_dir).encode() in argv:
            found.append((int(entry.name), int(fields[1])))
    return found


def checkpointed(run_dir: Path) -> bool:
    """Whether the run has logged past its first checkpoint (every 10 steps)."""
    try:
        steps = [json.loads(l).get("step") for l in (run_dir / "log.jsonl").read_text().splitlines() if l]
    except (OSError, ValueError):
        return False
    return (run_dir / "checkpoint.trgs").is_file() and max((s for s in steps if s), default=0) >= 14


@unittest.skipUnless((HAVE_RAY and TRGS) or REQUIRED, "needs Ray and TRGS_BIN")
class LocalClusterTest(unittest.TestCase):
    def test_killed_blocks_resume_and_merge(self):
        self.assertTrue(HAVE_RAY, "Ray is not installed (pip install python/trgs_ray)")
        self.assertTrue(Path(TRGS).is_file(), f"TRGS_BIN={TRGS!r} is not the trgs binary")
        d = Path(tempfile.mkdtemp(prefix="trgs-ray-cluster-"))
        trgs(
            "train",
            "--demo-scene",
            "window",
            "--demo-size",
            "64x48",
            "--iterations",
            "1",
            "--out",
            d / "demo",
        )
        trgs("split", d / "demo" / "dataset", "--blocks", "2", "--out", d / "blocks")
        runs, merged = d / "runs", d / "merged"
        cmd = [
            sys.executable,
            "-m",
            "trgs_ray",
            "run",
            str(d / "blocks"),
            "--runs",
            str(runs),
            "--out",
            str(merged),
            "--trgs",
            TRGS,
            "--poll-seconds",
            "0.5",
            "--",
            "--iterations",
            str(STEPS),
            "--checkpoint-every",
            "10",
            "--eval-every",
            str(STEPS),
            "--sh-degree",
            "1",
        ]
        driver = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        # block_0 loses its Ray worker (the task is retried by Ray, the orphaned trgs dies with
        # it), block_1 its trgs process (the task fails and is retried).
        kills = {"block_0": "worker", "block_1": "trgs"}
        deadline = time.monotonic() + 900
        while kills and driver.poll() is None and time.monotonic() < deadline:
            for name, what in list(kills.items()):
                procs = train_processes(runs / name)
                if procs and checkpointed(runs / name):
                    pid, parent = procs[0]
                    os.kill(parent if what == "worker" else pid, signal.SIGKILL)
                    del kills[name]
            time.sleep(0.2)
        out, _ = driver.communicate(timeout=max(1, deadline - time.monotonic()))
        self.assertEqual(driver.returncode, 0, out)
        self.assertEqual(kills, {}, f"not every block was killed mid-run:\n{out}")
        for name in ("block_0", "block_1"):
            self.assertIn(f"{name}: resumes from its checkpoint", out)
            log = (runs / name / "log.jsonl").read_text().splitlines()
            steps = [json.loads(l)["step"] for l in log if '"loss"' in l]
            self.assertEqual(steps, list(range(1, STEPS + 1)), f"{name}: every step once")
        report = json.loads((runs / "blocks_report.json").read_text())["blocks"]
        self.assertEqual([b["started_as"] for b in report], ["resume", "resume"])
        self.assertTrue(all(b["steps"] == STEPS and b["gaussians"] > 0 for b in report), report)
        self.assertTrue((merged / "model.ply").is_file(), out)
        self.assertIn("written to", out)
        again = subprocess.run(cmd, check=False, capture_output=True, text=True, timeout=300)
        self.assertEqual(again.returncode, 0, again.stdout + again.stderr)
        self.assertEqual(again.stdout.count("finished before; kept"), 2, again.stdout)
        print(out, file=sys.stderr)


if __name__ == "__main__":
    unittest.main()
