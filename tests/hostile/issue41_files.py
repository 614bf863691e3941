"""What issue 41's tests check on disk: `tree` records everything under a folder (hidden files and empty folders
too) so a refused run can be shown to have left the user's files byte-identical and added nothing; `bvh_folder` is a
small BVH source that `prepare` accepts."""

from __future__ import annotations

import hashlib
from pathlib import Path

from bounds_files import bvh_text, write


def tree(folder: Path) -> dict[str, str]:
    """Every path under ``folder``: a file by its bytes' SHA-256, a folder as "<dir>"."""
    return {p.relative_to(folder).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest() if p.is_file() else "<dir>"
            for p in sorted(folder.rglob("*"))}  # fmt: skip


def changed(before: dict[str, str], after: dict[str, str]) -> list[str]:
    """The paths added, removed or rewritten between two `tree`s."""
    return sorted(p for p in before.keys() | after.keys() if before.get(p) != after.get(p))


def bvh_folder(folder: Path, copies: int = 12) -> Path:
    """``copies`` BVH files of 40 frames on the shipped model's rig: enough clips for prepare's three splits."""
    text = bvh_text(40)
    for k in range(copies):
        write(folder / f"clip{k:02d}.bvh", text)
    return folder
