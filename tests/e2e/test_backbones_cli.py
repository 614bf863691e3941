"""MDM's ablation backbones through the real entry points: `train.py backbone=<name>` trains a few steps and leaves a
checkpoint that `sample.py` rebuilds (the backbone's options travel in the checkpoint) and samples from."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch
from cli_helpers import TINY, run_cli


@pytest.mark.slow
@pytest.mark.parametrize("backbone", ["trans_dec", "gru", "unet"])
def test_train_and_sample_with_backbone(tmp_path, backbone):
    run_cli("train.py", *TINY, f"backbone={backbone}", "trainer.max_steps=2", "checkpoint_every=2",
            "callbacks.evaluation.every_n_epochs=1000", env_dir=tmp_path)  # fmt: skip
    ckpt = next((tmp_path / "outputs").glob("train/*/checkpoints/last.ckpt"))
    saved = torch.load(ckpt, map_location="cpu", weights_only=True)
    assert saved["global_step"] == 2 and saved["hyper_parameters"]["backbone"]["name"] == backbone
    assert any(k.startswith("denoiser.backbone.") for k in saved["state_dict"])

    run_cli("sample.py", f"checkpoint={ckpt}", "text=a person walks", "num_samples=1", "length=1", "sampler=ddim",
            "steps=2", "export=none", env_dir=tmp_path)  # fmt: skip
    sample = json.loads(next((tmp_path / "outputs").glob("sample/*/results.json")).read_text())["samples"][0]
    joints = np.load(sample["joints"])
    assert joints.shape == (20, 22, 3) and np.isfinite(joints).all()
