"""Helpers for end-to-end tests: run the real entry points (train.py, sample.py), whole (argument checks, Hydra, the
error boundary, exit code): in this process by default (fixtures.in_process.call_main spares ~9 s of imports per
run), as a subprocess with ``process=True`` where the process itself is what is tested (its exit, a kill, several
processes)."""

from __future__ import annotations

import importlib
import os
import subprocess
import sys
from pathlib import Path

from fixtures.in_process import call_main

REPO = Path(__file__).resolve().parents[2]
# A model small enough to train a few steps in seconds; everything else is the shipped default config.
TINY = ["model.d_model=32", "model.num_layers=1", "model.num_heads=2", "model.ff_size=64", "logger=csv",
        "trainer.log_every_n_steps=1"]  # fmt: skip


# The caption-feature cache (text/cache.py: values keyed by encoder and caption, written atomically) is shared by
# every run of a session, as a user's runs share it; the rest of each run's cache stays its own. Set by conftest.py.
SHARED_TEXT_CACHE = "MOTIONDIFF_TEST_TEXT_CACHE"


def _link_text_cache(cache_dir: Path) -> None:
    shared = os.environ.get(SHARED_TEXT_CACHE)
    if shared and not (cache_dir / "text").exists():
        cache_dir.mkdir(parents=True, exist_ok=True)
        (cache_dir / "text").symlink_to(shared, target_is_directory=True)


def _script_main(script: str):
    """The function a root script (train.py, sample.py, ...) calls: motiondiff.cli.entry.<its stem>."""
    return getattr(importlib.import_module("motiondiff.cli.entry"), Path(script).stem)


def run_cli(script: str, *overrides: str, env_dir: Path, check: bool = True, timeout: int = 300,
            process: bool = False):  # fmt: skip
    """``python <script> *overrides`` with outputs and caches under ``env_dir``; ``timeout`` bounds a subprocess."""
    _link_text_cache(env_dir / "cache")
    env = {
        **os.environ,
        "MOTIONDIFF_OUTPUT_DIR": str(env_dir / "outputs"),
        "MOTIONDIFF_CACHE_DIR": str(env_dir / "cache"),
        "WANDB_MODE": "offline",
        "HYDRA_FULL_ERROR": "0",
    }
    if process:
        proc = subprocess.run([sys.executable, str(REPO / script), *overrides], cwd=env_dir, env=env,
                              capture_output=True, text=True, timeout=timeout)  # fmt: skip
    else:
        proc = call_main(_script_main(script), [str(REPO / script), *overrides], env_dir, env)
    if check and proc.returncode != 0:
        raise AssertionError(
            f"{script} {overrides} failed ({proc.returncode}):\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
        )
    return proc


def train_tiny(workdir: Path, *extra: str, process: bool = False) -> Path:
    run_cli("train.py", *TINY, "trainer.max_steps=4", "checkpoint_every=2", *extra, env_dir=workdir, process=process)
    ckpts = sorted((workdir / "outputs").glob("train/*/checkpoints/last.ckpt"))
    assert ckpts, "training left no checkpoint"
    return ckpts[-1]


def write_kit_layout(root: Path, num_clips: int = 12, seed: int = 0) -> Path:
    """A root in the official KIT-ML layout (new_joint_vecs/, texts/, Mean/Std, split files) with smooth random
    251-wide features: no KIT motion is shared, and the loader only needs the layout."""
    import numpy as np

    rng = np.random.default_rng(seed)
    (root / "new_joint_vecs").mkdir(parents=True)
    (root / "texts").mkdir()
    ids = [f"{i:05d}" for i in range(1, num_clips + 1)]
    for clip_id in ids:
        n = int(rng.integers(48, 120))
        feats = np.cumsum(rng.normal(scale=0.1, size=(n, 251)), axis=0).astype(np.float32)
        np.save(root / "new_joint_vecs" / f"{clip_id}.npy", feats)
        verb = ("walk", "wave", "jump")[int(clip_id) % 3]
        (root / "texts" / f"{clip_id}.txt").write_text(f"a person {verb}s.#a/DET person/NOUN {verb}/VERB#0.0#0.0\n")
    np.save(root / "Mean.npy", np.zeros(251, np.float32))
    np.save(root / "Std.npy", np.ones(251, np.float32))
    for split, part in (("train", ids[:8]), ("val", ids[8:10]), ("test", ids[10:])):
        (root / f"{split}.txt").write_text("\n".join(part) + "\n")
    return root
