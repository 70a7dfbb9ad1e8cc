"""`trgs-ray`: the blocks of `trgs split` on a Ray cluster (`run`), or one block for another
engine (`block`: a Slurm array task, a Kubernetes job)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .block import BlockFailed, BlockRun
from .driver import DriverOptions, find_trgs, run_blocks
from .manifest import read_manifest

EPILOG = """Arguments after `--` go to `trgs train` for every block, e.g.
  trgs-ray run blocks --runs runs --out merged -- --iterations 30000 --resolution 1600
A block that failed, or whose machine went away, starts again from its checkpoint; running the
same command again resumes every unfinished block and keeps the finished ones."""


def _command(sub, name: str, help: str) -> argparse.ArgumentParser:
    """A subcommand with the arguments both take: the split's folder, the runs' folder, trgs."""
    c = sub.add_parser(name, help=help, epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    c.add_argument("blocks", type=Path, help="the folder trgs split wrote (with blocks.json)")
    c.add_argument(
        "--runs", type=Path, required=True, help="where each block's run folder goes (RUNS/block_<k>)"
    )
    c.add_argument(
        "--trgs", help="the trgs binary, at the same path on every node [default: trgs on the PATH]"
    )
    return c


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="trgs-ray",
        description=__doc__,
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sub = p.add_subparsers(dest="command", required=True)

    run = _command(sub, "run", "train every block as a Ray task, then merge")
    run.add_argument("--out", type=Path, help="the merged run folder (omit to train without merging)")
    run.add_argument(
        "--address",
        help="the Ray cluster to join (e.g. auto, or ray://host:10001) [default: a new local one]",
    )
    run.add_argument(
        "--gpus-per-block",
        type=float,
        help="GPUs each block's task asks for [default: 1 where the cluster has GPUs, else 0]",
    )
    run.add_argument(
        "--cpus-per-block",
        type=float,
        help="CPUs each block's task asks for [default: 1 with a GPU, else a whole node's]",
    )
    run.add_argument(
        "--retries", type=int, default=3, help="attempts after the first for a block that fails [default: 3]"
    )
    run.add_argument("--poll-seconds", type=float, default=2.0, help=argparse.SUPPRESS)

    one = _command(sub, "block", "train one block (for Slurm array jobs and other engines)")
    one.add_argument(
        "--index",
        type=int,
        required=True,
        help="the block's index in the manifest (e.g. $SLURM_ARRAY_TASK_ID)",
    )
    return p


def main(argv=None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    train_args = []
    if "--" in argv:
        cut = argv.index("--")
        argv, train_args = argv[:cut], argv[cut + 1 :]
    a = parser().parse_args(argv)
    try:
        if a.command == "run":
            run_blocks(
                DriverOptions(
                    blocks_dir=a.blocks,
                    runs_dir=a.runs,
                    out=a.out,
                    trgs=a.trgs,
                    train_args=train_args,
                    address=a.address,
                    gpus_per_block=a.gpus_per_block,
                    cpus_per_block=a.cpus_per_block,
                    retries=a.retries,
                    poll_seconds=a.poll_seconds,
                )
            )
        else:
            blocks = read_manifest(a.blocks)
            if not 0 <= a.index < len(blocks):
                raise ValueError(
                    f"--index {a.index}: the manifest in {a.blocks} lists blocks 0 to {len(blocks) - 1}"
                )
            run = BlockRun(blocks[a.index], a.runs, find_trgs(a.trgs), train_args)
            outcome = run.run(lambda p: print(p.line(), flush=True))
            print(f"{outcome.name}: finished ({outcome.steps} steps, {outcome.gaussians} Gaussians)")
    except (ValueError, RuntimeError, BlockFailed) as e:
        print(f"trgs-ray: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
