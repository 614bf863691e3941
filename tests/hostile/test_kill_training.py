"""SIGKILL at three random points (while it writes) of training (each run resuming the last): every checkpoint loads,
half-written ones are removed by the next start, and training resumes."""

from __future__ import annotations

from pathlib import Path

import torch
from kill_runs import kill_points, killed, timed

TRAIN = ("model.d_model=32", "model.num_layers=1", "model.num_heads=2", "model.ff_size=64", "logger=csv",
         "condition=none", "checkpoint_every=1", "trainer.check_val_every_n_epoch=1000",
         "+trainer.limit_val_batches=0")  # fmt: skip


def newest_last(root: Path) -> Path | None:
    found = sorted(root.glob("*/checkpoints/last.ckpt"), key=lambda p: p.stat().st_mtime)
    return found[-1] if found else None


def test_training_killed_anywhere_leaves_loadable_checkpoints_and_resumes(tmp_path):
    times = timed(tmp_path, "train", *TRAIN, "trainer.max_steps=12")
    root = tmp_path / "outputs" / "train"
    for at in kill_points(times, seed=3):
        last = newest_last(root)  # each run resumes the last one's progress, as a user would after a crash
        resume = (f"ckpt_path={last}",) if last is not None else ()
        killed(tmp_path, "train", *TRAIN, "trainer.max_steps=100000", *resume, after=at)
        for ckpt in root.glob("*/checkpoints/[!.]*.ckpt"):  # .<name>.*.tmp.ckpt: a write cut by the kill
            state = torch.load(ckpt, map_location="cpu", weights_only=True)
            assert state["global_step"] > 0 and state["state_dict"], ckpt
    last = newest_last(root)
    step = torch.load(last, map_location="cpu", weights_only=True)["global_step"]
    timed(tmp_path, "train", *TRAIN, f"trainer.max_steps={step + 2}", f"ckpt_path={last}")
    final = torch.load(newest_last(root), map_location="cpu", weights_only=True)
    assert final["global_step"] == step + 2
    cut = sorted(p.name for p in root.glob("*/checkpoints/.*.tmp*"))
    assert cut == [], f"the next start did not remove the killed runs' half-written checkpoints: {cut}"
