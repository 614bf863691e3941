"""train_vae.py and the VAE level report end to end: a tiny VAE trains a few steps on the embedded data, writes its
checkpoints and run.json, and `python -m motiondiff.studies.vae_levels` scores it; a bad level is one clear error."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import pytest
import torch
from cli_helpers import run_cli
from fixtures.in_process import user_error

# 250 training clips at batch 128: 2 steps an epoch, validated after each, so 4 steps write a best-MPJPE checkpoint
# (and last.ckpt at step 4: checkpoint_every divides max_steps).
TINY_VAE = ["vae.d_model=32", "vae.num_layers=1", "vae.num_heads=2", "vae.ff_size=64", "vae.latent_dim=16",
            "logger=csv", "trainer.log_every_n_steps=1", "batch_size=128", "trainer.check_val_every_n_epoch=1",
            "trainer.max_steps=4", "checkpoint_every=2"]  # fmt: skip


@pytest.fixture(scope="module")
def vae_run(tmp_path_factory) -> Path:
    work = tmp_path_factory.mktemp("vae")
    # also the cosine schedule it shares with the diffusion module
    run_cli("train_vae.py", "level=action", "optim.schedule=cosine", "optim.warmup_steps=1", *TINY_VAE, env_dir=work)
    runs = sorted((work / "outputs" / "vae" / "action").iterdir())
    assert len(runs) == 1, runs
    return runs[0]


def test_train_vae_writes_checkpoints_logs_and_run_json(vae_run):
    last = vae_run / "checkpoints" / "last.ckpt"
    best = sorted((vae_run / "checkpoints").glob("best-mpjpe-*.ckpt"))
    assert last.is_file() and len(best) == 1
    ckpt = torch.load(last, map_location="cpu", weights_only=True)  # plain hyper-parameters, no pickled code
    hp = ckpt["hyper_parameters"]
    assert ckpt["global_step"] == 4 and hp["vae"]["tokens"] == 4 and hp["level"] == "action"
    assert len(hp["mean"]) == len(hp["std"]) == hp["feature_dim"] == 263 and hp["max_frames"] == 80
    run = json.loads((vae_run / "run.json").read_text())
    assert run["train_steps"] == 4 and run["tokens"] == 4 and run["best_checkpoint"] == str(best[0])
    assert 0 < run["best_val_mpjpe_m"] < 5
    rows = next(vae_run.glob("csv/*/metrics.csv")).read_text().splitlines()
    header = rows[0].split(",")
    assert {"train/recon", "train/kl", "val/recon", "val/kl", "val/mpjpe", "lr-AdamW"} <= set(header)
    lrs = [float(r.split(",")[header.index("lr-AdamW")]) for r in rows[1:] if r.split(",")[header.index("lr-AdamW")]]
    assert lrs[0] > lrs[-1] > 0  # cosine decay over the 4 steps


def test_vae_levels_report_scores_the_checkpoints(vae_run, tmp_path):
    ckpt = next((vae_run / "checkpoints").glob("best-mpjpe-*.ckpt"))
    out = tmp_path / "levels"
    # 31 test clips in small batches: one thread is as fast, and does not stall when another job is running
    env = {**os.environ, "MOTIONDIFF_OUTPUT_DIR": str(tmp_path / "outputs"), "MOTIONDIFF_CACHE_DIR": str(tmp_path),
           "OMP_NUM_THREADS": "1"}  # fmt: skip
    # the same checkpoint for all three levels: the pipeline, not the training, is under test
    args = [f"{lv}={ckpt}" for lv in ("motion", "action", "specific")] + [f"out={out}", "replications=2"]
    proc = subprocess.run([sys.executable, "-m", "motiondiff.studies.vae_levels", *args], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=300)  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-3000:]
    data = json.loads(out.with_suffix(".json").read_text())
    assert list(data["rows"]) == ["Real", "mean motion", "motion", "action", "specific"]
    mpjpes = [data["rows"][lv]["mpjpe"][0] for lv in ("motion", "action", "specific")]
    assert len(set(mpjpes)) == 1 and 0 < mpjpes[0] < 5  # same weights, same error, in metres
    assert data["rows"]["motion"]["mpjpe"][2] == 31  # one value per test clip
    assert all(math.isfinite(data["rows"][r]["fid"][0]) for r in data["rows"])
    assert data["levels"]["motion"]["step"] in (2, 4) and data["levels"]["motion"]["run_steps"] == 4
    text = out.with_suffix(".md").read_text()
    assert "| motion | 4 |" in text and "paper's trend (more tokens, better) on MPJPE: does not hold" in text


@pytest.mark.parametrize(
    "overrides, message",
    [(["level=huge"], "unknown level='huge'"), (["vae.tokens=0"], "vae.tokens must be a positive")],
)
def test_bad_level_is_one_clear_error(tmp_path, overrides, message):
    if overrides == ["level=huge"]:  # through the command line: exit code 2, one line
        proc = run_cli("train_vae.py", *overrides, env_dir=tmp_path, check=False)
        assert proc.returncode == 2
        assert message in proc.stderr and "Traceback" not in proc.stderr
    else:
        assert message in user_error("train_vae", tmp_path, *overrides)
    assert not list(tmp_path.glob("**/*.ckpt"))
