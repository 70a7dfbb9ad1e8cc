"""Run the blocks of `trgs split` on Ray (or any engine that runs one command per block).

`trgs split` writes block folders and a manifest (blocks.json); each block is an ordinary
`trgs train` run on its own folder, and `trgs merge` joins the trained blocks. This package
adds what a cluster needs around that: one task per block with the resources it asks for, a
block that fails or whose machine goes away started again from its checkpoint (`--resume`),
each block's progress on the driver's console, and the merge at the end.
"""

from .block import BlockOutcome, BlockRun, RunState
from .manifest import Block, read_manifest

__all__ = ["Block", "BlockOutcome", "BlockRun", "RunState", "read_manifest"]
