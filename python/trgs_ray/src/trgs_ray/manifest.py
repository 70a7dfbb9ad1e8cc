"""The manifest `trgs split` writes (blocks.json): the blocks and their folders."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

MANIFEST = "blocks.json"


@dataclass(frozen=True)
class Block:
    """One block of a split: its name, its scene folder and its test views."""

    name: str
    folder: Path
    train_views: int
    test_views: tuple[str, ...]


def read_manifest(blocks_dir: Path) -> list[Block]:
    """The blocks listed in `blocks_dir`/blocks.json, their folders made absolute.

    Raises ValueError naming the file when it is missing or is not a manifest of trgs split.
    """
    path = Path(blocks_dir) / MANIFEST
    try:
        data = json.loads(path.read_text())
    except FileNotFoundError:
        raise ValueError(
            f"{path}: no manifest (write one with: trgs split SCENE --blocks N --out {blocks_dir})"
        ) from None
    except (OSError, json.JSONDecodeError) as e:
        raise ValueError(f"{path}: cannot read the manifest of trgs split: {e}") from None
    try:
        blocks = [
            Block(
                name=str(b["name"]),
                folder=(path.parent / b["folder"]).resolve(),
                train_views=int(b["train_views"]),
                test_views=tuple(b["test_views"]),
            )
            for b in data["blocks"]
        ]
    except (KeyError, TypeError, ValueError) as e:
        raise ValueError(
            f"{path}: not a manifest of trgs split (expected blocks with name, folder, train_views, test_views): {e!r}"
        ) from None
    if not blocks:
        raise ValueError(f"{path}: the manifest lists no blocks")
    names = [b.name for b in blocks]
    if len(set(names)) != len(names):
        raise ValueError(f"{path}: block names repeat: {names}")
    return blocks
