"""`python train.py backbone=unet dataset=kit dataset.root=<KIT-ML layout>` runs; without the data it fails with
the one message that says where the files go and what layout they need."""

from __future__ import annotations

import pytest
import torch
from cli_helpers import TINY, run_cli, write_kit_layout


@pytest.mark.slow
def test_unet_on_kit_layout(tmp_path):
    root = write_kit_layout(tmp_path / "KIT-ML")
    run_cli("train.py", *TINY, "backbone=unet", "dataset=kit", "trainer.max_steps=2", f"dataset.root={root}",
            "checkpoint_every=2", env_dir=tmp_path)  # fmt: skip
    ckpt = next((tmp_path / "outputs").glob("train/*/checkpoints/last.ckpt"))
    saved = torch.load(ckpt, map_location="cpu", weights_only=True)
    hp = saved["hyper_parameters"]
    assert saved["global_step"] == 2 and hp["backbone"]["name"] == "unet"
    assert (hp["feature_dim"], hp["num_joints"], hp["fps"], hp["dataset"]) == (251, 21, 12.5, "kit")


def test_kit_without_data_names_the_layout(tmp_path):
    proc = run_cli("train.py", *TINY, "backbone=unet", "dataset=kit", "trainer.max_steps=2",
                   f"dataset.root={tmp_path / 'KIT-ML'}", env_dir=tmp_path, check=False)  # fmt: skip
    err = proc.stderr + proc.stdout
    assert proc.returncode != 0
    assert str(tmp_path / "KIT-ML") in err and "new_joint_vecs/<id>.npy" in err and "HumanML3D" in err
    assert "Traceback" not in err
