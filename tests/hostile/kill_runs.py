"""Killing a command at random points (test_kill_*.py): each test first times one complete run (T), then kills ten
runs, the k-th at a random moment in the k-th tenth of T (so start-up, work and the final writes are all hit), and
checks what is on disk after every kill: the old complete result or the new complete one."""

from __future__ import annotations

import os
import signal
import subprocess
import time
from pathlib import Path

import numpy as np
from hostile_cli import REPO, popen_cli, run_cli

KILLS = 10
BANDAI = REPO.parent / "shared" / "data" / "bandai-namco" / "bandai-ds1.zip"
HYDRA_START = {".hydra", ".motiondiff.lock"}  # what a run has written before its first result


def kill_points(duration: float, seed: int) -> list[float]:
    rng = np.random.default_rng(seed)
    return [float(rng.uniform(k, k + 1) * duration / KILLS) for k in range(KILLS)]


def timed(tmp: Path, name: str, *args: str) -> float:
    start = time.perf_counter()
    proc = run_cli(tmp, name, *args)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return time.perf_counter() - start


def killed(tmp: Path, name: str, *args: str, after: float) -> None:
    """Start ``motiondiff-<name> *args`` in ``tmp`` and SIGKILL it (and any worker it started) ``after`` seconds."""
    proc = popen_cli(tmp, name, *args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        proc.wait(timeout=after)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
