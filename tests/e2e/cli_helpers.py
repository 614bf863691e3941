"""Helpers for end-to-end tests: run the real entry points (train.py, sample.py) as subprocesses."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
# A model small enough to train a few steps in seconds; everything else is the shipped default config.
TINY = ["model.d_model=32", "model.num_layers=1", "model.num_heads=2", "model.ff_size=64", "logger=csv",
        "trainer.log_every_n_steps=1"]  # fmt: skip


def run_cli(script: str, *overrides: str, env_dir: Path, check: bool = True, timeout: int = 300):
    env = {
        **os.environ,
        "MOTIONDIFF_OUTPUT_DIR": str(env_dir / "outputs"),
        "MOTIONDIFF_CACHE_DIR": str(env_dir / "cache"),
        "WANDB_MODE": "offline",
        "HYDRA_FULL_ERROR": "0",
    }
    proc = subprocess.run(
        [sys.executable, str(REPO / script), *overrides],
        cwd=env_dir,
        env=env,
        capture_output=True,
        text=True,
        timeout=timeout,
    )
    if check and proc.returncode != 0:
        raise AssertionError(
            f"{script} {overrides} failed ({proc.returncode}):\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
        )
    return proc


def train_tiny(workdir: Path, *extra: str) -> Path:
    run_cli("train.py", *TINY, "trainer.max_steps=4", "checkpoint_every=2", *extra, env_dir=workdir)
    ckpts = sorted((workdir / "outputs").glob("train/*/checkpoints/last.ckpt"))
    assert ckpts, "training left no checkpoint"
    return ckpts[-1]
