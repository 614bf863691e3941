"""What a path that should be a readable file is instead, in words a user can act on: not there, a folder, a pipe or
device (`/dev/zero` is not "not found"), a link that loops, unreadable, or empty. Every input a command reads
(a model file, a prompts file, an edit's motion, a body model) is checked through `file_problem`, and each caller
raises its own error with it, so the same path is described the same way everywhere."""

from __future__ import annotations

import errno
import os
import stat
from pathlib import Path

NAME_MAX = 255  # bytes in one file or folder name (Linux, macOS and Windows file systems alike)


def file_problem(path: str | os.PathLike, allow_empty: bool = False) -> str | None:
    """None for a readable regular file (non-empty unless ``allow_empty``), else what ``path`` is, as the end of a
    sentence that starts with the path ("not found (relative to ...)", "is a folder", ...)."""
    path = Path(path)
    try:
        info = path.stat()
    except OSError as err:
        if err.errno == errno.ELOOP:
            return "is a symbolic link that loops"
        if err.errno == errno.ENOENT or not os.path.lexists(path):
            where = "" if path.is_absolute() else f" (relative to {Path.cwd()})"
            return f"not found{where}"
        return f"cannot be read ({err.strerror})"
    if stat.S_ISDIR(info.st_mode):
        return "is a folder, not a file"
    if not stat.S_ISREG(info.st_mode):
        return "is a pipe or device, not a file"
    if not os.access(path, os.R_OK):
        return "is not readable by this user (permission denied): check its permissions"
    if info.st_size == 0 and not allow_empty:
        return "is empty (0 bytes)"
    return None


def over_long_name(path: str | os.PathLike) -> str | None:
    """The first part of ``path`` longer than a file system takes (NAME_MAX bytes), None when every part fits."""
    return next((part for part in Path(path).parts if len(os.fsencode(part)) > NAME_MAX), None)
