"""An edit's input path checked before it is read: a readable, non-empty regular file, or one EditError that says
what the path is instead (a folder, a pipe or device, a link loop, a file this user may not read) and what to do."""

from __future__ import annotations

import errno
import os
from pathlib import Path

from motiondiff.edit.masks import EditError


def check_input_file(path: Path) -> None:
    """A readable regular file, or one EditError that says what the path is instead (a folder, a pipe or device,
    a link loop, a file this user may not read, an empty file) and what to do."""
    try:
        path.stat()
    except OSError as err:
        if err.errno == errno.ELOOP:
            raise EditError(f"input {path} is a symbolic link that loops; point it at a motion file") from None
        if not os.path.lexists(path) or err.errno == errno.ENOENT:
            raise EditError(f"input {path} not found (relative to {Path.cwd()}); check the path") from None
        raise EditError(f"input {path} cannot be read ({err.strerror}); check the path") from None
    if path.is_dir():
        raise EditError(f"input {path} is a folder: give a .bvh/.npy/.npz file inside it")
    if not path.is_file():
        raise EditError(f"input {path} is a pipe or device, not a file: give a .bvh/.npy/.npz file")
    if not os.access(path, os.R_OK):
        raise EditError(f"input {path} is not readable by this user (permission denied): check its permissions")
    if path.stat().st_size == 0:
        raise EditError(f"input {path} is empty (0 bytes): give a motion file with frames in it")
