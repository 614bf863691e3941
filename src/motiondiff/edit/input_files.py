"""An edit's input path checked before it is read: a readable, non-empty regular file, or one EditError that says
what the path is instead (`runtime.file_kinds`: a folder, a pipe or device, a link loop, a file this user may not
read) and what to do."""

from __future__ import annotations

from pathlib import Path

from motiondiff.edit.masks import EditError
from motiondiff.runtime.file_kinds import file_problem


def check_input_file(path: Path) -> None:
    """A readable regular file with something in it, or one EditError naming what ``path`` is instead."""
    problem = file_problem(path)
    if problem is not None:
        raise EditError(f"input {path} {problem}: give a .bvh/.npy/.npz motion file (or a dataset clip id)")
