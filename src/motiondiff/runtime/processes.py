"""Processes and their pid locks: whether a process is alive (how a lock or a temporary folder named by a pid is told
from one a killed run left), and taking such a lock."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path


def alive(pid: int) -> bool:
    """True for a running process, this one and other users' included (signal 0 checks without sending)."""
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except PermissionError:
        return True
    except OSError:
        return False
    return True


def take_lock(lock: Path, content: str, refuse_if_held: Callable[[], None]) -> None:
    """Create ``lock`` exclusively (O_EXCL) holding ``content`` (the holder's pid first). Where it exists,
    ``refuse_if_held()`` raises while its holder is alive; otherwise the lock is stale (its process was killed) and is
    replaced. One place for the pid locks of run folders and dataset preparation."""
    while True:
        try:
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            break
        except FileExistsError:
            refuse_if_held()
            lock.unlink(missing_ok=True)
    with os.fdopen(fd, "w") as f:
        f.write(content)
