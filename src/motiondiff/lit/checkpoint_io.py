"""Checkpoints written to a temporary file beside the target and renamed into place.

Lightning's own save goes through an fsspec transaction whose temporary file lives in the system temp folder; when
that is another filesystem than the run's, the final move is a copy into the target, and a kill during the copy
leaves a truncated checkpoint under the real name. A temporary file in the same folder makes the rename atomic.
torch's zip writer reports a full disk as a RuntimeError ("enforce fail ... unexpected pos"); it is raised again as
the OSError (ENOSPC) it is, so the command says to free disk space.
"""

from __future__ import annotations

import errno
import os
import shutil
from pathlib import Path
from typing import Any

import torch
from lightning.pytorch.plugins.io import TorchCheckpointIO

from motiondiff.runtime.atomic import atomic_write


class AtomicCheckpointIO(TorchCheckpointIO):
    def save_checkpoint(self, checkpoint: dict[str, Any], path, storage_options: Any | None = None) -> None:
        if storage_options is not None:
            raise TypeError("AtomicCheckpointIO takes no storage_options")
        os.makedirs(os.path.dirname(os.fspath(path)) or ".", exist_ok=True)
        atomic_write(Path(path), lambda tmp: _save(checkpoint, tmp, path), suffix=".ckpt")


FULL_BELOW = 1 << 20  # bytes left on the disk after a failed write that mean the write filled it


def _save(checkpoint: dict[str, Any], tmp: str, path) -> None:
    try:
        torch.save(checkpoint, tmp)
    except RuntimeError as err:
        if shutil.disk_usage(os.path.dirname(tmp) or ".").free < FULL_BELOW:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), os.fspath(path)) from err
        raise
