"""`python train.py backbone=unet dataset=kit dataset.root=<KIT-ML layout>` runs; without the data it fails with
the one message that says where the files go and what layout they need."""

from __future__ import annotations

import json
import zipfile
from pathlib import Path

import numpy as np
import pytest
import torch
from cli_helpers import TINY, run_cli, write_kit_layout
from fixtures.in_process import user_error


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
    assert proc.returncode == 2
    assert str(tmp_path / "KIT-ML") in err and "new_joint_vecs/<id>.npy" in err and "HumanML3D" in err
    assert "Traceback" not in err


@pytest.mark.slow
def test_bvh_folder_dataset_trains_with_rotations(tmp_path, shared):
    """`dataset=bvh dataset.root=<zip of BVH>`: prepared once into the cache, then trained on 6D rotations."""
    zip_path = shared("data", "bandai-namco", "bandai-ds1.zip")
    names = [n for n in zipfile.ZipFile(zip_path).namelist() if n.endswith(".bvh")]
    rows = [f"{Path(n).name},{Path(n).stem.split('_')[1]},{Path(n).stem.split('_')[2]}," for n in names]
    labels = tmp_path / "labels.csv"
    labels.write_text("file,action,style,caption\n" + "\n".join(rows) + "\n")  # content/style from the file names
    args = [
        *TINY,
        "dataset=bvh",
        f"dataset.root={zip_path}",
        "dataset.datamodule.max_clip_frames=60",
        f"dataset.datamodule.labels={labels}",
        "representation=rp6jr",
        "loss=geometric",
        "condition=action",
        "trainer.max_steps=2",
        "checkpoint_every=2",
    ]
    run_cli("train.py", *args, env_dir=tmp_path)
    cache = tmp_path / "cache" / "bvh_prepared"
    assert (cache / "meta.json").is_file() and (cache / "joint_map.json").is_file()
    stamp = (cache / "train.npz").stat().st_mtime_ns
    run_cli("train.py", *args, env_dir=tmp_path)  # same sources and options: the cache is reused
    assert (cache / "train.npz").stat().st_mtime_ns == stamp
    ckpt = sorted((tmp_path / "outputs").glob("train/*/checkpoints/last.ckpt"))[-1]
    hp = torch.load(ckpt, map_location="cpu", weights_only=True)["hyper_parameters"]
    assert hp["representation"]["name"] == "rp6jr" and hp["representation"]["rig"]["joint_names"][0] == "Hips"
    assert hp["representation"]["joint_map"]["target"] == "smpl22" and len(hp["action_names"]) > 5


def test_bvh_dataset_without_files_names_the_layout(tmp_path):
    err = user_error("train", tmp_path, *TINY, "dataset=bvh", f"dataset.root={tmp_path / 'mocap'}",
                     "trainer.max_steps=2")  # fmt: skip
    assert str(tmp_path / "mocap") in err and "*.bvh" in err


@pytest.mark.slow
@pytest.mark.parametrize("dataset", ["humanact12", "uestc"])
def test_action_datasets_train_in_their_pickled_layouts(tmp_path, dataset):
    """MDM's action-to-motion setting (rp6jr + geometric losses) on a fixture in ACTOR's exact layout."""
    from fixtures.action_layouts import write_humanact12_fixture, write_uestc_fixture

    root = tmp_path / dataset
    (write_humanact12_fixture if dataset == "humanact12" else write_uestc_fixture)(root)
    run_cli("train.py", *TINY, f"dataset={dataset}", f"dataset.root={root}", "condition=action", "loss=geometric",
            "trainer.max_steps=2", "checkpoint_every=2", env_dir=tmp_path)  # fmt: skip
    ckpt = next((tmp_path / "outputs").glob("train/*/checkpoints/last.ckpt"))
    hp = torch.load(ckpt, map_location="cpu", weights_only=True)["hyper_parameters"]
    assert hp["representation"]["name"] == "rp6jr" and hp["representation"]["rig"]["name"] == "smpl24"
    assert hp["feature_dim"] == 3 + 6 * 24 and hp["loss"]["lambda_foot"] == 1.0
    assert len(hp["action_names"]) == (12 if dataset == "humanact12" else 40)
    run_cli("sample.py", f"checkpoint={ckpt}", f"action={hp['action_names'][0]}", "num_samples=1", "length=1",
            "sampler=ddim", "steps=2", "export=none", env_dir=tmp_path)  # fmt: skip
    sample = json.loads(next((tmp_path / "outputs").glob("sample/*/results.json")).read_text())["samples"][0]
    assert np.load(sample["joints"]).shape == (20, 24, 3)


@pytest.mark.parametrize("dataset", ["humanact12", "uestc"])
def test_action_dataset_without_files_names_the_layout(tmp_path, dataset):
    err = user_error("train", tmp_path, *TINY, f"dataset={dataset}", f"dataset.root={tmp_path / 'none'}",
                     "condition=action", "trainer.max_steps=2")  # fmt: skip
    assert str(tmp_path / "none") in err
    assert ("humanact12poses.pkl" if dataset == "humanact12" else "vibe_cache_refined.pkl") in err
