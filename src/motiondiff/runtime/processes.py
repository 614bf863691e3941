"""Whether a process is alive: how a lock or a temporary folder named by a pid is told from one a killed run left."""

from __future__ import annotations

import os


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
