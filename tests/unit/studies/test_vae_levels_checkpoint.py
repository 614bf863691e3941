"""vae_levels picks a level's VAE from the newest run by the MPJPE saved in its best files, not by file time."""

from __future__ import annotations

import os

import torch

from motiondiff.studies.vae_levels import newest_checkpoint


def _best_file(path, mpjpe: float, mtime: int) -> None:
    state = {"callbacks": {"ModelCheckpoint{'monitor': 'val/mpjpe'}": {"monitor": "val/mpjpe",
                                                                      "current_score": torch.tensor(mpjpe)}}}  # fmt: skip
    path.parent.mkdir(parents=True, exist_ok=True)
    torch.save(state, path)
    os.utime(path, (mtime, mtime))


def test_the_newest_runs_lowest_saved_mpjpe_not_its_newest_file(tmp_path):
    old_run, new_run = (
        tmp_path / "vae" / "motion" / "a" / "checkpoints",
        tmp_path / "vae" / "motion" / "b" / "checkpoints",
    )
    _best_file(old_run / "best-mpjpe-step0000900.ckpt", 0.01, 1_000)  # an older run's, better: not this run's
    _best_file(new_run / "best-mpjpe-step0000200.ckpt", 0.05, 2_000)  # the newest run's best
    _best_file(new_run / "best-mpjpe-step0000400.ckpt", 0.08, 3_000)  # left by a resumed sitting: newer, worse
    assert newest_checkpoint("motion", tmp_path) == new_run / "best-mpjpe-step0000200.ckpt"
