"""The blocks of a split as Ray tasks: one `trgs train` per block with the resources it asks
for, retried from its checkpoint when it fails or its worker dies, its progress printed here as
it goes, and `trgs merge` once every block has finished."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

from .block import BlockOutcome, BlockRun
from .manifest import Block, read_manifest

REPORT_FILE = "blocks_report.json"


@dataclass
class DriverOptions:
    blocks_dir: Path
    runs_dir: Path
    out: Path | None
    trgs: str | None = None
    train_args: list = field(default_factory=list)
    address: str | None = None
    gpus_per_block: float | None = None
    cpus_per_block: float | None = None
    retries: int = 3
    poll_seconds: float = 2.0


def find_trgs(given: str | None) -> str:
    """The trgs binary: the path given, else `trgs` on the PATH (every node must have it at the
    same path)."""
    if given:
        path = Path(given).expanduser()
        if not path.is_file() or not os.access(path, os.X_OK):
            raise ValueError(f"{given}: not an executable trgs binary")
        return str(path.resolve())
    found = shutil.which("trgs")
    if not found:
        raise ValueError(
            "no trgs binary on the PATH: install it (cargo install --path apps/trgs-cli) or pass --trgs PATH"
        )
    return found


def block_resources(cluster: dict, nodes: list, gpus: float | None, cpus: float | None) -> tuple:
    """(GPUs, CPUs) each block's task asks for: one GPU each where the cluster has GPUs, else
    none; with a GPU one CPU, without one a whole node's CPUs (trgs then renders on a CPU Vulkan
    driver that uses every core, so two blocks on one node would only take turns)."""
    if gpus is None:
        gpus = 1.0 if cluster.get("GPU", 0) >= 1 else 0.0
    if cpus is None:
        if gpus > 0:
            cpus = 1.0
        else:
            cpus = (
                max((n.get("Resources", {}).get("CPU", 0) for n in nodes if n.get("Alive")), default=1.0)
                or 1.0
            )
    return gpus, cpus


def adapter_for_gpu(gpu_ids: list) -> str | None:
    """The PCI bus address of the first GPU Ray gave the task, for TRGS_ADAPTER (Vulkan ignores
    CUDA_VISIBLE_DEVICES, which is how Ray hands out GPUs); None where nvidia-smi cannot say."""
    if not gpu_ids or not shutil.which("nvidia-smi"):
        return None
    try:
        out = subprocess.run(
            ["nvidia-smi", "--query-gpu=pci.bus_id", "--format=csv,noheader", "-i", str(gpu_ids[0])],
            capture_output=True,
            text=True,
            timeout=30,
            check=True,
        ).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return None
    return vulkan_bus_id(out)


def vulkan_bus_id(nvidia_smi: str) -> str | None:
    """nvidia-smi's bus id (00000001:1B:00.0) as wgpu's Vulkan adapter names it (0001:1b:00.0),
    the PCI domain kept: GPU virtual machines put each GPU in a domain of its own, all at bus 0.
    None where wgpu names no bus id (it leaves it empty at bus 0 device 0), so that trgs takes
    its default adapter rather than match none."""
    domain, _, rest = nvidia_smi.strip().partition(":")
    try:
        domain = f"{int(domain, 16):04x}"
    except ValueError:
        return None
    if not rest or rest.lower().startswith("00:00."):
        return None
    return f"{domain}:{rest.lower()}"


def _block_task(
    block: Block, runs_dir: str, trgs: str, train_args: list, progress, poll_seconds: float
) -> dict:
    """The body of a block's Ray task (see run_blocks)."""
    import ray  # a worker imports Ray anyway; the module stays importable without it

    env = dict(os.environ)
    if "TRGS_ADAPTER" not in env:
        gpu_ids = ray.get_gpu_ids()
        bus = adapter_for_gpu(gpu_ids)
        if bus:
            env["TRGS_ADAPTER"] = bus
        elif gpu_ids:
            # trgs then takes its default adapter, whichever GPU Ray gave this task.
            progress.report.remote(
                f"{block.name}: no PCI bus id for GPU {gpu_ids[0]} (nvidia-smi missing, or a GPU at bus 0 "
                "device 0, which Vulkan names none): it trains on trgs's default GPU; set TRGS_ADAPTER per "
                "worker, or run one block a node"
            )
    run = BlockRun(block, Path(runs_dir), trgs, train_args, env=env)
    return run.run(lambda p: progress.report.remote(p.line()), poll_seconds).to_json()


def run_blocks(o: DriverOptions, echo=print) -> list:
    """Train every block of `o.blocks_dir` on the Ray cluster at `o.address` (a new local one when
    None), then merge them into `o.out` (unless None). Returns the blocks' outcomes."""
    import ray

    blocks = read_manifest(o.blocks_dir)
    trgs = find_trgs(o.trgs)
    runs_dir = Path(o.runs_dir).resolve()
    runs_dir.mkdir(parents=True, exist_ok=True)
    started_here = not ray.is_initialized()
    if started_here:
        ray.init(address=o.address, include_dashboard=False, log_to_driver=False)
    try:
        gpus, cpus = block_resources(ray.cluster_resources(), ray.nodes(), o.gpus_per_block, o.cpus_per_block)
        echo(
            f"{len(blocks)} blocks on Ray ({_cluster_line(ray.cluster_resources())}); each block asks for {gpus:g} GPU and {cpus:g} CPU"
        )

        @ray.remote(num_cpus=0)
        class ProgressBoard:
            """The blocks' latest progress lines, for the driver to print."""

            def __init__(self):
                self.lines = []

            def report(self, line: str):
                self.lines.append(line)

            def take(self) -> list:
                out, self.lines = self.lines, []
                return out

        # On the driver's own node: were it placed on a node that dies, the driver's next read
        # of it would raise and end the run, not just that node's blocks (which Ray retries).
        from ray.util.scheduling_strategies import NodeAffinitySchedulingStrategy

        here = NodeAffinitySchedulingStrategy(node_id=ray.get_runtime_context().get_node_id(), soft=False)
        board = ProgressBoard.options(scheduling_strategy=here).remote()
        task = ray.remote(_block_task).options(
            num_gpus=gpus,
            num_cpus=cpus,
            # A failed `trgs train` raises and a lost worker or node fails the task: either way
            # the next attempt finds the checkpoint and resumes.
            max_retries=o.retries,
            retry_exceptions=True,
        )
        pending = {
            task.remote(b, str(runs_dir), trgs, o.train_args, board, o.poll_seconds): b.name for b in blocks
        }
        outcomes, failed = {}, {}
        while pending:
            done, _ = ray.wait(list(pending), num_returns=1, timeout=o.poll_seconds)
            for line in ray.get(board.take.remote()):
                echo(line)
            for ref in done:
                name = pending.pop(ref)
                try:
                    outcomes[name] = BlockOutcome(**ray.get(ref))
                    echo(f"{name}: finished")
                except (ray.exceptions.RayError, TypeError) as e:  # the last attempt's error
                    failed[name] = e
                    echo(f"{name}: failed after {o.retries + 1} attempts: {e}")
        for line in ray.get(board.take.remote()):
            echo(line)
    finally:
        if started_here:
            ray.shutdown()
    ordered = [outcomes[b.name] for b in blocks if b.name in outcomes]
    write_report(runs_dir / REPORT_FILE, ordered)
    echo(summary_table(ordered))
    if failed:
        names = ", ".join(sorted(failed))
        raise RuntimeError(
            f"{len(failed)} of {len(blocks)} blocks failed ({names}); run again to resume them"
        )
    if o.out is not None:
        merge(trgs, Path(o.blocks_dir), runs_dir, Path(o.out), echo)
    return ordered


def merge(trgs: str, blocks_dir: Path, runs_dir: Path, out: Path, echo=print) -> None:
    """`trgs merge` of the trained blocks into `out`."""
    cmd = [trgs, "merge", str(blocks_dir), "--runs", str(runs_dir), "--out", str(out)]
    echo("merging: " + " ".join(cmd))
    done = subprocess.run(cmd, check=False, capture_output=True, text=True)
    if done.stdout:
        echo(done.stdout.rstrip())
    if done.returncode != 0:
        raise RuntimeError(f"trgs merge failed ({done.returncode}): {done.stderr.strip()}")


def write_report(path: Path, outcomes: list) -> None:
    """The blocks' outcomes as JSON, written to a temporary file and renamed into place."""
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_text(json.dumps({"blocks": [o.to_json() for o in outcomes]}, indent=2))
    os.replace(tmp, path)


def summary_table(outcomes: list) -> str:
    """One line per block: steps, Gaussians, test PSNR, peak memory, time."""

    def mib(b):
        return "-" if b is None else f"{b / 2**20:.0f}"

    rows = ["block      started  steps  Gaussians  test PSNR  peak GPU MiB  peak RAM MiB  train s"]
    for o in outcomes:
        psnr = "-" if o.test_psnr is None else f"{o.test_psnr:.2f}"
        secs = "-" if o.train_seconds is None else f"{o.train_seconds:.0f}"
        rows.append(
            f"{o.name:<10} {o.started_as:<8} {o.steps:>5}  {o.gaussians or 0:>9}  {psnr:>9}  "
            f"{mib(o.peak_gpu_bytes):>12}  {mib(o.peak_ram_bytes):>12}  {secs:>7}"
        )
    return "\n".join(rows)


def _cluster_line(res: dict) -> str:
    return f"{res.get('CPU', 0):g} CPUs, {res.get('GPU', 0):g} GPUs"
