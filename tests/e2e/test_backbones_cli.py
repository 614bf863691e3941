"""MDM's ablation backbones through the entry points' configs and runs: `train.py backbone=<name>` trains a few
steps and leaves a checkpoint that `sample.py` rebuilds (the backbone's options travel in the checkpoint) and
samples from. In-process (`fixtures.in_process`): the command line itself is tested with unet on KIT's layout."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch
from cli_helpers import TINY
from fixtures.in_process import run_entry


@pytest.mark.slow
@pytest.mark.parametrize("backbone", ["trans_dec", "gru", "unet"])
def test_train_and_sample_with_backbone(tmp_path, backbone):
    _, run = run_entry("train", tmp_path / "train", *TINY, f"backbone={backbone}", "trainer.max_steps=2",
                       "checkpoint_every=2", "callbacks.evaluation.every_n_epochs=1000")  # fmt: skip
    ckpt = run / "checkpoints" / "last.ckpt"
    saved = torch.load(ckpt, map_location="cpu", weights_only=True)
    assert saved["global_step"] == 2 and saved["hyper_parameters"]["backbone"]["name"] == backbone
    assert any(k.startswith("denoiser.backbone.") for k in saved["state_dict"])

    _, run = run_entry("sample", tmp_path / "sample", f"checkpoint={ckpt}", "text=a person walks", "num_samples=1",
                       "length=1", "sampler=ddim", "steps=2", "export=none")  # fmt: skip
    sample = json.loads((run / "results.json").read_text())["samples"][0]
    joints = np.load(sample["joints"])
    assert joints.shape == (20, 22, 3) and np.isfinite(joints).all()
