"""A block's run without Ray: fresh, failed, resumed from its checkpoint, kept when finished;
the manifest's errors; the resources a block asks for. A stand-in for `trgs train` writes a run
folder as trgs does (marker, log, checkpoint, results), so these run in a second."""

import contextlib
import io
import json
import os
import stat
import sys
import tempfile
import textwrap
import unittest
from pathlib import Path

from trgs_ray.block import BlockFailed, BlockRun, LogTail, RunState, run_state
from trgs_ray.cli import main
from trgs_ray.driver import block_resources, vulkan_bus_id
from trgs_ray.manifest import read_manifest

FAKE_TRGS = textwrap.dedent(
    """\
    import json, os, sys
    from pathlib import Path
    args = sys.argv[1:]
    assert args[0] == "train", args
    out = Path(args[args.index("--out") + 1])
    resume = "--resume" in args
    if os.environ.get("FAKE_REFUSE"):
        sys.exit("refused: this block has finished")
    held = Path(os.environ.get("FAKE_HELD", "/nonexistent"))
    if held.is_file() and int(held.read_text()) > 0:
        held.write_text(str(int(held.read_text()) - 1))
        sys.exit(f"Error: {out} is in use by another training run (process 7 on gone): wait")
    if os.environ.get("FAKE_OTHER"):
        sys.exit("Error: the camera of the training view a.png is not the one the run started with")
    if resume:
        cfg = json.loads((out / "fake_config.json").read_text())
        start = int((out / "checkpoint.trgs").read_text())
        log = [l for l in (out / "log.jsonl").read_text().splitlines() if json.loads(l)["step"] <= start]
    else:
        out.mkdir(parents=True, exist_ok=True)
        cfg = {"iterations": int(args[args.index("--iterations") + 1])}
        (out / "fake_config.json").write_text(json.dumps(cfg))
        start, log = 0, []
    (out / "unfinished-run.json").write_text(json.dumps({"iterations": cfg["iterations"], "checkpoint_step": start}))
    fail_after = int(os.environ.get("FAKE_FAIL_AFTER", "0")) if not resume else 0
    for step in range(start + 1, cfg["iterations"] + 1):
        log.append(json.dumps({"step": step, "loss": 1.0 / step, "psnr": 20.0 + step,
                               "gaussians": 100 + step, "gpu_bytes": 1000 * step, "peak_ram_bytes": 7}))
        (out / "log.jsonl").write_text("\\n".join(log) + "\\n")
        if step % 5 == 0:
            (out / "checkpoint.trgs").write_text(str(step))
            (out / "unfinished-run.json").write_text(json.dumps({"iterations": cfg["iterations"], "checkpoint_step": step}))
            if fail_after and step >= fail_after:
                print("the device was lost", flush=True)
                sys.exit(3)
    (out / "model.ply").write_text("ply")
    (out / "metrics.json").write_text(json.dumps({"steps": cfg["iterations"], "gaussians": 42, "planes": 1,
                                                 "psnr": 30.5, "train_seconds": 1.0}))
    (out / "unfinished-run.json").unlink()
    print("done", flush=True)
    """
)


class BlockFixture(unittest.TestCase):
    """A manifest of one block and the stand-in trgs."""

    def setUp(self):
        self.dir = Path(tempfile.mkdtemp(prefix="trgs-ray-block-"))
        fake = self.dir / "trgs"
        fake.write_text(f"#!{sys.executable}\n{FAKE_TRGS}")
        fake.chmod(fake.stat().st_mode | stat.S_IXUSR)
        self.trgs = str(fake)
        blocks = self.dir / "blocks"
        (blocks / "block_0").mkdir(parents=True)
        manifest = {
            "blocks": [{"name": "block_0", "folder": "block_0", "train_views": 9, "test_views": ["a.png"]}]
        }
        (blocks / "blocks.json").write_text(json.dumps(manifest))
        self.block = read_manifest(blocks)[0]
        self.runs = self.dir / "runs"


class BlockRunTest(BlockFixture):
    def run_block(self, **env):
        lines = []
        run = BlockRun(self.block, self.runs, self.trgs, ["--iterations", "12"], env={**os.environ, **env})
        return run, run.run(lambda p: lines.append(p.line()), poll_seconds=0.05), lines

    def logged_steps(self):
        return [json.loads(l)["step"] for l in (self.runs / "block_0" / "log.jsonl").read_text().splitlines()]

    def test_a_fresh_block_trains_to_its_end(self):
        _, outcome, lines = self.run_block()
        self.assertEqual(outcome.started_as, "fresh")
        self.assertEqual((outcome.steps, outcome.gaussians, outcome.test_psnr), (12, 42, 30.5))
        self.assertEqual(outcome.peak_gpu_bytes, 12000)
        self.assertEqual(lines[0], "block_0: starts")
        self.assertIn("block_0: step 12", lines[-1])
        self.assertIs(run_state(self.runs / "block_0"), RunState.DONE)

    def test_a_failed_block_resumes_from_its_checkpoint(self):
        run = BlockRun(
            self.block,
            self.runs,
            self.trgs,
            ["--iterations", "12"],
            env={**os.environ, "FAKE_FAIL_AFTER": "5"},
        )
        with self.assertRaises(BlockFailed) as failed:
            run.run(lambda p: None, poll_seconds=0.05)
        message = str(failed.exception)
        self.assertIn("status 3", message)
        self.assertIn("the device was lost", message, "the output's last lines are quoted")
        self.assertIs(run_state(self.runs / "block_0"), RunState.RESUME)
        self.assertEqual(run.command(RunState.RESUME)[-1], "--resume")
        self.assertNotIn("--iterations", run.command(RunState.RESUME), "a resumed run keeps its own settings")
        for given in (["--target-memory", "512"], ["--target-memory=512"]):
            resumed = BlockRun(self.block, self.runs, self.trgs, ["--iterations", "12", *given])
            self.assertEqual(resumed.command(RunState.RESUME)[-len(given):], given, "the machine's memory goes on")
        _, outcome, lines = self.run_block()
        self.assertEqual(outcome.started_as, "resume")
        self.assertIn("resumes from its checkpoint at step 5", lines[0])
        self.assertEqual(self.logged_steps(), list(range(1, 13)), "every step logged once")
        out = (self.runs / "block_0.out").read_text()
        self.assertEqual(out.count("== "), 2, "both attempts' output is kept")

    def test_a_folder_held_by_a_dead_node_is_waited_for(self):
        held = self.dir / "held"
        held.write_text("2")
        lines = []
        env = {**os.environ, "FAKE_HELD": str(held)}
        run = BlockRun(self.block, self.runs, self.trgs, ["--iterations", "12"], env=env, lock_wait=0.01)
        outcome = run.run(lambda p: lines.append(p.line()), poll_seconds=0.05)
        self.assertEqual(outcome.started_as, "fresh")
        self.assertEqual(sum("folder is held" in l for l in lines), 2, lines)
        held.write_text("5")
        (self.runs / "block_0" / "metrics.json").unlink()
        short = BlockRun(self.block, self.runs, self.trgs, [], env=env, lock_wait=0.01, lock_wait_total=0.02)
        with self.assertRaisesRegex(BlockFailed, "in use by another training run"):
            short.run(lambda p: None, poll_seconds=0.05)
        # Held once, then another failure: that one is not waited on, though the refusal before
        # it is still among the output's last lines.
        held.write_text("1")
        out = self.runs / "block_0.out"
        attempts = out.read_text().count("\n== ")
        env_other = {**env, "FAKE_OTHER": "1"}
        other = BlockRun(self.block, self.runs, self.trgs, [], env=env_other, lock_wait=0.01, lock_wait_total=60.0)
        with self.assertRaises(BlockFailed):
            other.run(lambda p: None, poll_seconds=0.05)
        self.assertEqual(out.read_text().count("\n== ") - attempts, 2, "the refused attempt and the failed one")

    def test_a_finished_block_is_kept(self):
        self.run_block()
        _, outcome, lines = self.run_block(FAKE_REFUSE="1")
        self.assertEqual(outcome.started_as, "done")
        self.assertEqual(lines, ["block_0: finished before; kept"])

    def test_the_log_is_read_again_when_a_resume_cuts_it(self):
        log = self.dir / "log.jsonl"
        log.write_text('{"step": 1}\n{"step": 2}\n{"st')
        tail = LogTail(log)
        self.assertEqual([e["step"] for e in tail.read()], [1, 2])
        log.write_text('{"step": 1}\n')
        self.assertEqual([e["step"] for e in tail.read()], [1])
        with open(log, "a") as f:
            f.write('{"step": 2}\n')
        self.assertEqual([e["step"] for e in tail.read()], [2])


class BlockCommandTest(BlockFixture):
    """`trgs-ray block`, the command a Slurm array task runs."""

    def test_one_block_by_its_index(self):
        blocks = str(self.dir / "blocks")
        argv = ["block", blocks, "--runs", str(self.runs), "--trgs", self.trgs]
        with contextlib.redirect_stdout(io.StringIO()) as out:
            self.assertEqual(main([*argv, "--index", "0", "--", "--iterations", "12"]), 0)
        self.assertIn("block_0: finished (12 steps, 42 Gaussians)", out.getvalue())
        with contextlib.redirect_stderr(io.StringIO()) as err:
            self.assertEqual(main([*argv, "--index", "1"]), 1)
        self.assertIn("--index 1: the manifest in", err.getvalue())


class ManifestTest(unittest.TestCase):
    def test_errors_name_the_file(self):
        d = Path(tempfile.mkdtemp(prefix="trgs-ray-manifest-"))
        with self.assertRaisesRegex(ValueError, r"blocks\.json: no manifest .*trgs split"):
            read_manifest(d)
        (d / "blocks.json").write_text('{"blocks": [{"name": "b"}]}')
        with self.assertRaisesRegex(ValueError, r"blocks\.json: not a manifest of trgs split"):
            read_manifest(d)
        (d / "blocks.json").write_text("{")
        with self.assertRaisesRegex(ValueError, r"blocks\.json: cannot read"):
            read_manifest(d)


class BusIdTest(unittest.TestCase):
    def test_the_pci_domain_is_kept_and_bus_zero_is_left_to_trgs(self):
        self.assertEqual(vulkan_bus_id("00000000:1B:00.0"), "0000:1b:00.0")
        self.assertEqual(vulkan_bus_id("00000001:3C:00.0"), "0001:3c:00.0")
        self.assertIsNone(vulkan_bus_id("00000002:00:00.0"), "wgpu names no bus id there")
        self.assertIsNone(vulkan_bus_id(""))


class ResourcesTest(unittest.TestCase):
    def test_a_block_takes_a_gpu_or_a_whole_node(self):
        nodes = [{"Alive": True, "Resources": {"CPU": 16.0}}, {"Alive": False, "Resources": {"CPU": 64.0}}]
        self.assertEqual(block_resources({"GPU": 8.0, "CPU": 16.0}, nodes, None, None), (1.0, 1.0))
        self.assertEqual(block_resources({"CPU": 16.0}, nodes, None, None), (0.0, 16.0))
        self.assertEqual(block_resources({"GPU": 8.0}, nodes, 2.0, 4.0), (2.0, 4.0))


if __name__ == "__main__":
    unittest.main()
