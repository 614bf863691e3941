"""How much a .npy or .npz file asks for, read from its headers before any array is loaded: a few MB of .npz can
inflate to GBs (a zip of zeros), and a .npy header can declare any shape."""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np

MAX_ARRAY_BYTES = 256 * 2**20  # one array of a motion file (a million frames of 22 joints in float32)


def check_array_file(path: str | Path, limit: int = MAX_ARRAY_BYTES) -> None:
    """ValueError naming the file, the array and the fix when an array of ``path`` (.npy, or each member of a .npz)
    would take more than ``limit`` bytes. Unreadable files pass: loading them reports the problem."""
    path = Path(path)
    if zipfile.is_zipfile(path):
        with zipfile.ZipFile(path) as z:
            for info in z.infolist():
                _check(path, info.filename, info.file_size, limit)
        return
    fmt = np.lib.format
    try:
        with open(path, "rb") as f:
            version = fmt.read_magic(f)
            read = {(1, 0): fmt.read_array_header_1_0, (2, 0): fmt.read_array_header_2_0}.get(version)
            if read is None:
                return
            shape, _, dtype = read(f)
    except (ValueError, OSError, EOFError):
        return
    _check(path, "its array", int(np.prod(shape, dtype=np.float64)) * dtype.itemsize, limit)


def _check(path: Path, name: str, size: int, limit: int) -> None:
    if size > limit:
        raise ValueError(f"{path}: {name} takes {size / 2**20:.0f} MB, more than the {limit // 2**20} MB a motion "
                         "file's array may be; cut the motion into shorter files")  # fmt: skip
