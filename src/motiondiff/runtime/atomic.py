"""Crash-safe file writes: everything the project saves goes through `atomic_write`."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable
from pathlib import Path


def atomic_write(path: str | os.PathLike, write: Callable[[str], object], suffix: str = "") -> Path:
    """Call `write(tmp)` on a temporary file beside `path`, then rename it into place, so a failure leaves either
    the old file or the new one, never a half-written one. `suffix` ends the temp name (tools that pick the format
    from the extension, such as np.save or matplotlib, need it). The file gets the usual umask permissions."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp" + suffix, dir=path.parent)
    os.close(fd)
    try:
        write(tmp)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600 files
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


TEMP_GLOB = ".*.tmp*"  # what atomic_write leaves when its process is killed mid-write


def save_npy(path: str | os.PathLike, array) -> Path:
    """``np.save`` through `atomic_write`: a crash or a full disk leaves no truncated array under the final name."""
    import numpy as np

    return atomic_write(path, lambda tmp: np.save(tmp, array), suffix=".npy")


def write_json(path: str | os.PathLike, data, **dumps) -> Path:
    """JSON through `atomic_write`, strict: a NaN or infinity is an error here, never a bare ``NaN`` in the file."""
    import json

    text = json.dumps(data, indent=1, allow_nan=False, **dumps)
    return atomic_write(path, lambda tmp: Path(tmp).write_text(text))


def finite_or_null(data):
    """``data`` with every NaN or infinite float replaced by None (JSON null): for metrics that can be undefined
    (a distance over too few motions), which strict JSON cannot hold as numbers."""
    import math

    if isinstance(data, float):
        return data if math.isfinite(data) else None
    if isinstance(data, dict):
        return {k: finite_or_null(v) for k, v in data.items()}
    if isinstance(data, list | tuple):
        return [finite_or_null(v) for v in data]
    if hasattr(data, "item") and getattr(data, "ndim", None) == 0:  # numpy / torch scalars
        return finite_or_null(data.item())
    return data
