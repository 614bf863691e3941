"""Which of a run's best-metric checkpoints (best-fid-*.ckpt, best-mpjpe-*.ckpt) is the best, read from the files.

Lightning's ModelCheckpoint remembers its top-k files in memory and in the checkpoints it writes. A run resumed from a
last.ckpt that was written before a later best file (the step checkpoint is saved at the batch's end, the evaluation
runs after it) knows nothing of that file, so a folder can hold two "best" files and the newer name is not always the
lower score. Each best file still carries the score it was kept for (its own `current_score`), so the choice is made
from the files themselves.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from pathlib import Path

from motiondiff.runtime.checked_loading import torch_load
from motiondiff.runtime.errors import UsageError


def stored_score(path: str | Path, monitor: str) -> float | None:
    """The ``monitor`` value (e.g. "val/fid") the checkpoint at ``path`` was saved for; None when it holds none (a
    step checkpoint, or a file another program wrote). An unreadable file raises the loader's UsageError."""
    for state in torch_load(path).get("callbacks", {}).values():
        if isinstance(state, dict) and state.get("monitor") == monitor and state.get("current_score") is not None:
            return float(state["current_score"])
    return None


def ranked(
    paths: Iterable[str | Path], monitor: str, mode: str = "min", damaged: list | None = None
) -> list[tuple[float, Path]]:
    """(score, path) of every file that holds a ``monitor`` score, best first (``mode`` "min" or "max"); NaN counts
    as the worst, as Lightning saves it. An unreadable file raises its UsageError, or, given a ``damaged`` list, is
    left out and its error appended there."""
    worst = math.inf if mode == "min" else -math.inf
    scored = []
    for path in paths:
        try:
            score = stored_score(path, monitor)
        except UsageError as err:
            if damaged is None:
                raise
            damaged.append(err)
            continue
        if score is not None:
            scored.append((worst if math.isnan(score) else score, Path(path)))
    return sorted(scored, key=lambda item: item[0], reverse=mode == "max")


def best_of(paths: Iterable[str | Path], monitor: str, mode: str = "min") -> Path | None:
    """The file with the best stored ``monitor`` score, or None when none holds one."""
    found = ranked(paths, monitor, mode)
    return found[0][1] if found else None
