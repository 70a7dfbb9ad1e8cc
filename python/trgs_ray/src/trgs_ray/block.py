"""One block's `trgs train` run: started fresh, resumed from its checkpoint, or left as it is
when it has finished, its progress read from the run's log as it grows.

Nothing here needs Ray: a Slurm array job or a Kubernetes job runs the same code through
`trgs-ray block`, so every engine resumes a block the same way.
"""

from __future__ import annotations

import ctypes
import enum
import json
import signal
import subprocess
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Callable

from .manifest import Block

# The run folder's files (trgs_train::run): the checkpoint a run resumes from, the marker of a
# run that has not written its results, and the log of its steps and evaluations.
CHECKPOINT_FILE = "checkpoint.trgs"
UNFINISHED_MARKER = "unfinished-run.json"
LOG_FILE = "log.jsonl"
METRICS_FILE = "metrics.json"


class RunState(enum.Enum):
    """What a block's run folder holds before an attempt."""

    FRESH = "fresh"  # nothing to continue: a new run
    RESUME = "resume"  # a checkpoint of an unfinished run: continue it
    DONE = "done"  # finished: its results are written


def run_state(run_dir: Path) -> RunState:
    """The state of the run folder `run_dir` (see RunState)."""
    run_dir = Path(run_dir)
    finished = (run_dir / METRICS_FILE).is_file() and (run_dir / "model.ply").is_file()
    if finished and not (run_dir / UNFINISHED_MARKER).exists():
        return RunState.DONE
    if (run_dir / CHECKPOINT_FILE).is_file():
        return RunState.RESUME
    return RunState.FRESH


class BlockFailed(RuntimeError):
    """A block's `trgs train` ended with an error (the engine retries it from its checkpoint)."""


@dataclass
class BlockOutcome:
    """A finished block: what the summary table and the report show."""

    name: str
    run_dir: str
    started_as: str
    steps: int
    gaussians: int | None
    planes: int | None
    test_psnr: float | None
    peak_gpu_bytes: int | None
    peak_ram_bytes: int | None
    train_seconds: float | None
    attempt_seconds: float

    def to_json(self) -> dict:
        return asdict(self)


@dataclass
class Progress:
    """The latest of a block's log: its step, training PSNR, Gaussians, last evaluation."""

    block: str
    step: int | None = None
    psnr: float | None = None
    gaussians: int | None = None
    eval_step: int | None = None
    eval_psnr: float | None = None
    note: str | None = None

    def line(self) -> str:
        parts = [self.block + ":"]
        if self.note:
            parts.append(self.note)
        if self.step is not None:
            parts.append(f"step {self.step}")
            if self.psnr is not None:
                parts.append(f"train PSNR {self.psnr:.2f} dB")
            if self.gaussians is not None:
                parts.append(f"{self.gaussians} Gaussians")
        if self.eval_psnr is not None:
            parts.append(f"test PSNR {self.eval_psnr:.2f} dB at step {self.eval_step}")
        return " ".join(parts)


@dataclass
class LogTail:
    """Reads the lines a run appends to its log; starts over when the log shrinks (a resumed
    run cuts it back to its checkpoint's step)."""

    path: Path
    offset: int = 0
    pending: bytes = b""

    def read(self) -> list:
        try:
            size = self.path.stat().st_size
        except FileNotFoundError:
            return []
        if size < self.offset:
            self.offset, self.pending = 0, b""
        with open(self.path, "rb") as f:
            f.seek(self.offset)
            data = f.read()
        self.offset += len(data)
        data = self.pending + data
        *complete, self.pending = data.split(b"\n")
        out = []
        for raw in complete:
            try:
                out.append(json.loads(raw))
            except ValueError:
                continue
        return out


# prctl, looked up before any fork: the child calls it between fork and exec, where a threaded
# parent (a Ray worker) must not take locks such as the dynamic loader's.
_PRCTL = ctypes.CDLL(None, use_errno=True).prctl if sys.platform.startswith("linux") else None
_PR_SET_PDEATHSIG = 1


def _die_with_parent() -> None:
    """In the child before exec: die when the process that started it dies, so that a killed
    worker leaves no `trgs train` holding the run folder's lock."""
    if _PRCTL is not None:
        _PRCTL(_PR_SET_PDEATHSIG, signal.SIGKILL)


def _machine_args(train_args: list) -> list:
    """The arguments of `train_args` that `trgs train --resume` accepts: --target-memory, as
    `--target-memory N` or `--target-memory=N` (the last one given)."""
    out = []
    for i, arg in enumerate(train_args):
        if arg == "--target-memory" and i + 1 < len(train_args):
            out = [arg, train_args[i + 1]]
        elif arg.startswith("--target-memory="):
            out = [arg]
    return out


# What `trgs train` says when another process holds the run folder: after a node died, its lock
# outlives it for a while (an NFS lease; ten minutes where the file system has no locks, while
# trgs waits for the dead holder's heartbeat to go stale).
HELD_BY_ANOTHER_RUN = "in use by another training run"


class BlockRun:
    """One block's run folder and the `trgs train` that fills it. An attempt refused because
    the folder is held is made again every `lock_wait` seconds for up to `lock_wait_total`
    (Ray retries a task at once, well inside a dead node's lock)."""

    def __init__(
        self,
        block: Block,
        runs_dir: Path,
        trgs: str,
        train_args: list,
        env: dict | None = None,
        lock_wait: float = 60.0,
        lock_wait_total: float = 720.0,
    ):
        self.block = block
        self.run_dir = Path(runs_dir) / block.name
        self.trgs = trgs
        self.train_args = list(train_args)
        self.env = env
        self.lock_wait = lock_wait
        self.lock_wait_total = lock_wait_total

    def command(self, state: RunState) -> list:
        """The `trgs train` command for an attempt from `state`: a resumed run takes its settings
        from its checkpoint, so the training arguments go only to a fresh one, but for the
        machine's --target-memory, which a resume takes anew (the way out of a GPU out of
        memory that trgs names)."""
        if state is RunState.RESUME:
            return [self.trgs, "train", "--out", str(self.run_dir), "--resume", *_machine_args(self.train_args)]
        return [
            self.trgs,
            "train",
            "--data",
            str(self.block.folder),
            "--out",
            str(self.run_dir),
            *self.train_args,
        ]

    def run(self, report: Callable[[Progress], None], poll_seconds: float = 2.0) -> BlockOutcome:
        """Train the block to its end (or leave it when it has finished) and say how it went;
        `report` hears its progress. Raises BlockFailed when `trgs train` fails."""
        state = run_state(self.run_dir)
        t0 = time.monotonic()
        if state is RunState.DONE:
            report(Progress(self.block.name, note="finished before; kept"))
            return self.outcome(state, t0)
        self.run_dir.mkdir(parents=True, exist_ok=True)
        tail = LogTail(self.run_dir / LOG_FILE)
        progress = Progress(self.block.name)
        if state is RunState.RESUME:
            step = _checkpoint_step(self.run_dir)
            progress.note = "resumes from its checkpoint" + (f" at step {step}" if step else "")
        else:
            progress.note = "starts"
        report(progress)
        progress.note = None
        # The command's own output, every attempt's, beside the run folder (the run folder is
        # set aside whole when a fresh run starts there).
        output = self.run_dir.parent / f"{self.block.name}.out"
        waited = 0.0
        while True:
            before = output.stat().st_size if output.exists() else 0
            rc = self._launch(state, output, tail, progress, report, poll_seconds)
            if rc == 0:
                return self.outcome(state, t0)
            last = _last_lines(output, 12)
            if HELD_BY_ANOTHER_RUN in _written_since(output, before) and waited < self.lock_wait_total:
                report(Progress(self.block.name, note=f"its folder is held; trying again in {self.lock_wait:.0f} s"))
                time.sleep(self.lock_wait)
                waited += self.lock_wait
                state = run_state(self.run_dir)
                continue
            raise BlockFailed(
                f"{self.block.name}: trgs train exited with {_exit_text(rc)}; its output ({output}) ends:\n{last}"
            )

    def _launch(self, state: RunState, output: Path, tail, progress: Progress, report, poll_seconds: float) -> int:
        """One `trgs train` from `state`, its output appended to `output`, its progress reported;
        returns its exit status."""
        with open(output, "ab") as out:
            out.write(f"\n== {time.strftime('%Y-%m-%d %H:%M:%S')} {' '.join(self.command(state))}\n".encode())
            out.flush()
            child = subprocess.Popen(
                self.command(state),
                stdout=out,
                stderr=subprocess.STDOUT,
                stdin=subprocess.DEVNULL,
                env=self.env,
                # Only a call through a function pointer runs in the child (see _PRCTL).
                preexec_fn=_die_with_parent if _PRCTL is not None else None,  # noqa: PLW1509
            )
            try:
                while True:
                    try:
                        rc = child.wait(timeout=poll_seconds)
                    except subprocess.TimeoutExpired:
                        rc = None
                    if _update(progress, tail.read()):
                        report(progress)
                    if rc is not None:
                        break
            finally:
                if child.poll() is None:
                    child.kill()
                    child.wait()
        return rc

    def outcome(self, state: RunState, t0: float) -> BlockOutcome:
        """The finished run's figures, from its metrics.json and its log."""
        metrics = {}
        try:
            metrics = json.loads((self.run_dir / METRICS_FILE).read_text())
        except (OSError, ValueError):
            pass
        peak_gpu = peak_ram = None
        steps = 0
        for e in LogTail(self.run_dir / LOG_FILE).read():
            if isinstance(e.get("step"), int):
                steps = max(steps, e["step"])
            if isinstance(e.get("gpu_bytes"), int):
                peak_gpu = max(peak_gpu or 0, e["gpu_bytes"])
            if isinstance(e.get("peak_ram_bytes"), int):
                peak_ram = max(peak_ram or 0, e["peak_ram_bytes"])
        return BlockOutcome(
            name=self.block.name,
            run_dir=str(self.run_dir),
            started_as=state.value,
            steps=int(metrics.get("steps") or steps),
            gaussians=metrics.get("gaussians"),
            planes=metrics.get("planes"),
            test_psnr=metrics.get("psnr"),
            peak_gpu_bytes=peak_gpu,
            peak_ram_bytes=peak_ram,
            train_seconds=metrics.get("train_seconds"),
            attempt_seconds=time.monotonic() - t0,
        )


def _update(p: Progress, entries: list) -> bool:
    """Fold new log entries into `p`; whether anything changed."""
    changed = False
    for e in entries:
        if isinstance(e.get("step"), int) and "loss" in e:
            p.step, p.psnr, p.gaussians = e["step"], e.get("psnr"), e.get("gaussians")
            changed = True
        ev = e.get("eval")
        if isinstance(ev, dict) and ev.get("psnr") is not None:
            p.eval_step, p.eval_psnr = ev.get("step"), ev["psnr"]
            changed = True
    return changed


def _checkpoint_step(run_dir: Path) -> int | None:
    """The step of the checkpoint an unfinished run resumes from (its marker says)."""
    try:
        step = json.loads((run_dir / UNFINISHED_MARKER).read_text()).get("checkpoint_step")
    except (OSError, ValueError, AttributeError):
        return None
    return step if isinstance(step, int) else None


def _exit_text(rc: int) -> str:
    if rc < 0:
        try:
            return f"signal {signal.Signals(-rc).name}"
        except ValueError:
            return f"signal {-rc}"
    return f"status {rc}"


def _written_since(path: Path, offset: int) -> str:
    """What was appended to `path` after its first `offset` bytes (one attempt's output)."""
    try:
        with open(path, "rb") as f:
            f.seek(offset)
            return f.read().decode(errors="replace")
    except OSError:
        return ""


def _last_lines(path: Path, n: int) -> str:
    try:
        lines = path.read_text(errors="replace").splitlines()
    except OSError:
        return ""
    return "\n".join(lines[-n:])
