"""Multi-process training with Lightning DDP (`trainer=ddp`): two CPU processes over gloo, each with half of the
global batch, against one process with the whole batch. Both start from the same weights (same seed); their per-step
noise draws differ, so the curves are compared on averages, not step by step. The generation evaluation and the
best-FID checkpoint run too (8 clips, DDIM-5, to keep the test short), and rank 0 alone renders one short sample
video per evaluation."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
from cli_helpers import TINY, run_cli

STEPS = 32  # two epochs of the embedded data at a global batch of 16 (251 clips / 16 = 16 steps each)
COMMON = [*TINY, f"trainer.max_steps={STEPS}", f"checkpoint_every={STEPS}", "optim.lr=2e-3",
          "trainer.check_val_every_n_epoch=1", "callbacks.evaluation.num_clips=8", "callbacks.evaluation.steps=5",
          "callbacks.evaluation.videos.prompts=[a person walks forward]",
          "callbacks.evaluation.videos.seconds=1"]  # fmt: skip


def metrics(workdir: Path) -> dict[str, dict[int, float]]:
    (run,) = (workdir / "outputs" / "train").glob("*/csv/version_0/metrics.csv")
    out: dict[str, dict[int, float]] = {}
    with open(run) as f:
        for row in csv.DictReader(f):
            for key in ("train/loss", "val/loss", "val/fid"):
                if row.get(key):
                    out.setdefault(key, {})[int(row["step"])] = float(row[key])
    return out


def test_two_process_ddp_follows_the_single_process_curve_at_the_same_global_batch(tmp_path):
    single, ddp = tmp_path / "single", tmp_path / "ddp"
    single.mkdir(), ddp.mkdir()
    run_cli("train.py", *COMMON, "batch_size=16", env_dir=single, timeout=600)
    run_cli("train.py", *COMMON, "trainer=ddp", "batch_size=8", env_dir=ddp, timeout=600, process=True)
    (run_dir,) = (ddp / "outputs" / "train").glob("*")
    assert (run_dir / "train_ddp_process_1.log").is_file(), "the second process did not run"
    one, two = metrics(single), metrics(ddp)
    assert len(one["train/loss"]) == len(two["train/loss"]) == STEPS
    # per-step training losses are noisy (random t per sample): compare their means over the run
    mean_one, mean_two = np.mean(list(one["train/loss"].values())), np.mean(list(two["train/loss"].values()))
    assert abs(mean_two - mean_one) < 0.1 * mean_one, (mean_one, mean_two)
    # val/loss (fixed noise per batch) is reduced over both processes' halves of the validation set (sync_dist)
    assert sorted(two["val/loss"]) == sorted(one["val/loss"]) and len(two["val/loss"]) == STEPS // 16
    curve_one = [one["val/loss"][s] for s in sorted(one["val/loss"])]
    curve_two = [two["val/loss"][s] for s in sorted(two["val/loss"])]
    assert curve_one[-1] < curve_one[0] and curve_two[-1] < curve_two[0], (curve_one, curve_two)
    assert np.allclose(curve_two, curve_one, rtol=0.05), (curve_one, curve_two)
    # the generation metrics run on every process (same weights, same seed) and the best-FID checkpoint is kept once
    assert sorted(two["val/fid"]) == sorted(one["val/fid"])
    assert len(list((run_dir / "checkpoints").glob("best-fid-*.ckpt"))) == 1
    ckpt = run_dir / "checkpoints" / "last.ckpt"
    assert ckpt.is_file() and len(list((ddp / "outputs" / "train").glob("*/run.json"))) == 1
    assert len(list(run_dir.glob("videos/step*/*.gif"))) == STEPS // 16  # one per evaluation, from rank 0 only
