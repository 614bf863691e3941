"""Killing a command at random points (test_kill_*.py): each test first times one complete run, from its start to its
first write on disk (S: the imports before it write nothing, so a kill there tests nothing) and to its end (T), then
kills three runs, the k-th at a random moment in the k-th third of [S, T] (so the run folder's start, the work and the
final writes are all hit), and checks what is on disk after every kill: the old complete result or the new one."""

from __future__ import annotations

import os
import signal
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np
from hostile_cli import REPO, popen_cli

KILLS = 3
BANDAI = REPO.parent / "shared" / "data" / "bandai-namco" / "bandai-ds1.zip"
# a small, quick `prepare` of the real data (one clip per group, 40 frames): the commands these tests stop or race
PREPARE = ("bandai", "--src", str(BANDAI), "--per-group", "1", "--max-frames", "40", "--compact", "--workers", "1",
           "--caption-variants", "0", "--rare-to-train", "0")  # fmt: skip
HYDRA_START = {".hydra", ".motiondiff.lock"}  # what a run has written before its first result


def kill_points(times: tuple[float, float], seed: int) -> list[float]:
    """KILLS moments (s after the start), the k-th uniform in the k-th of KILLS equal parts of [S, T] = ``times``."""
    first_write, end = times
    rng = np.random.default_rng(seed)
    return [float(first_write + rng.uniform(k, k + 1) * (end - first_write) / KILLS) for k in range(KILLS)]


def timed(tmp: Path, name: str, *args: str) -> tuple[float, float]:
    """Run ``motiondiff-<name> *args`` in ``tmp`` to its end (it must succeed); (S, T): seconds from its start to the
    first new file or folder under ``tmp``, and to its end."""
    before = set(tmp.rglob("*"))
    with tempfile.TemporaryFile("w+") as err:  # not under tmp, and never a full pipe while we poll
        start = time.perf_counter()
        proc = popen_cli(tmp, name, *args, stdout=subprocess.DEVNULL, stderr=err)
        first_write = None
        while first_write is None and proc.poll() is None:
            if any(p not in before for p in tmp.rglob("*")):
                first_write = time.perf_counter() - start
            else:
                time.sleep(0.05)
        proc.wait()
        end = time.perf_counter() - start
        err.seek(0)
        assert proc.returncode == 0, err.read()[-3000:]
    return (end if first_write is None else first_write), end


def killed(tmp: Path, name: str, *args: str, after: float) -> None:
    """Start ``motiondiff-<name> *args`` in ``tmp`` and SIGKILL it (and any worker it started) ``after`` seconds."""
    proc = popen_cli(tmp, name, *args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        proc.wait(timeout=after)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
