"""HumanAct12 / UESTC loaders on fixtures written in the official pickled layouts (tests/fixtures/action_layouts.py)."""

from __future__ import annotations

import importlib.util
import os
import pickle
from pathlib import Path

import numpy as np
import pytest

from motiondiff.data.representations.hml_features import features_from_canonical
from motiondiff.data.sources.humanact12 import ACTION_NAMES, load_humanact12
from motiondiff.data.sources.smpl_clips import place_points
from motiondiff.data.sources.uestc import VIBE_TO_SMPL, load_uestc
from motiondiff.geometry.skeleton import SMPL22
from motiondiff.runtime.errors import DatasetNotFoundError
from motiondiff.runtime.safe_pickle import load_pickle

_spec = importlib.util.spec_from_file_location(
    "action_layouts", Path(__file__).parents[2] / "fixtures" / "action_layouts.py"
)
layouts = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(layouts)

FK_TOLERANCE = 1e-4  # metres


@pytest.fixture(scope="module")
def humanact12_root(tmp_path_factory):
    root = tmp_path_factory.mktemp("humanact12")
    return root, layouts.write_humanact12_fixture(root, num_clips=24, seed=0)


@pytest.fixture(scope="module")
def uestc_root(tmp_path_factory):
    root = tmp_path_factory.mktemp("uestc")
    return root, layouts.write_uestc_fixture(root, num_clips=14, seed=1)


def _raw(path: Path) -> dict:
    with open(path, "rb") as f:
        return pickle.load(f)


def _check_canonical(clip):
    m = clip.motion
    assert m.joints.shape == (m.num_frames, 22, 3) and m.rotations.shape == (m.num_frames, 24, 4)
    assert m.root.shape == (m.num_frames, 3) and m.offsets.shape == (24, 3)
    assert abs(m.joints[..., 1].min()) < 1e-5 and np.abs(m.joints[0, 0, [0, 2]]).max() < 1e-5
    rig = m.rig_positions()
    assert abs(rig[..., 1].min()) < 1e-5 and np.abs(rig[0, 0, [0, 2]]).max() < 1e-5
    # facing +Z at frame 0: hips + shoulders across (right -> left, HumanML3D's rule) points along +x
    across = rig[0, 1] - rig[0, 2] + rig[0, 16] - rig[0, 17]
    assert across[0] > 0 and abs(across[2]) < 1e-5


def test_humanact12_clips_labels_and_splits(humanact12_root):
    root, truth = humanact12_root
    train = load_humanact12(root, "train")
    assert len(train.clips) == 24 and train.fps == 20.0 and train.action_names == list(ACTION_NAMES)
    assert train.feature_skeleton is SMPL22 and train.rig.name == "smpl24"
    assert [c.action for c in train.clips] == truth["labels"]
    np.testing.assert_allclose(train.rig.offsets, np.mean(truth["offsets"], axis=0), atol=1e-6)
    clip = train.clips[3]
    assert clip.meta["captions_generated"] and clip.texts == ["a person performs jump."]
    assert clip.meta["source_up_axis"] == "-y"
    for c in train.clips:
        _check_canonical(c)
    assert features_from_canonical(clip.motion.joints, SMPL22).shape == (clip.motion.num_frames - 1, 263)
    test, val = load_humanact12(root, "test"), load_humanact12(root, "val")
    assert [c.id for c in test.clips] == [c.id for c in train.clips]  # official: evaluation uses every clip
    assert len(val.clips) == 24  # 2 clips per action, all kept (10 per action at most)
    np.testing.assert_array_equal(val.rig.offsets, train.rig.offsets)


def test_humanact12_fk_reproduces_joints3d(humanact12_root):
    root, truth = humanact12_root
    raw = _raw(root / "humanact12poses.pkl")
    worst = 0.0
    for clip in load_humanact12(root, "train").clips:
        i = clip.meta["index"]
        expected = place_points(raw["joints3D"][i], clip.meta["placement"])
        worst = max(worst, np.abs(clip.motion.rig_positions() - expected).max())
        np.testing.assert_allclose(clip.motion.offsets, truth["offsets"][i], atol=1e-5)
    assert worst <= FK_TOLERANCE


def test_source_up_axis_is_detected_and_undone(tmp_path):
    clips = {}
    for up in ("-y", "+z", "+y"):
        layouts.write_humanact12_fixture(tmp_path / up, num_clips=3, seed=7, up=up)
        split = load_humanact12(tmp_path / up, "train")
        assert split.clips[0].meta["source_up_axis"] == up
        clips[up] = split.clips
    for a, b in zip(clips["-y"], clips["+z"], strict=True):
        np.testing.assert_allclose(a.motion.joints, b.motion.joints, atol=1e-4)
        np.testing.assert_allclose(a.motion.rig_positions(), b.motion.rig_positions(), atol=1e-4)


def test_uestc_cross_subject_splits(uestc_root):
    root, truth = uestc_root
    train, test, val = (load_uestc(root, s) for s in ("train", "test", "val"))
    subjects = {s: {c.meta["subject"] for c in split.clips} for s, split in [("train", train), ("test", test)]}
    assert subjects["train"] <= set(layouts.UESTC_TRAIN) and subjects["test"] <= set(layouts.UESTC_TEST)
    ids = {c.id for c in train.clips + test.clips}
    assert "a3_d8_p003_c2" not in ids  # camera 2 at view 8 is dropped from both
    short = truth["names"][5].removesuffix("_color.avi")
    assert short not in ids  # a train clip under 45 frames (ACTOR: 3/4 of 60)
    assert len(train.clips) == 8 and len(test.clips) == 4 and [c.id for c in val.clips] == [c.id for c in test.clips]
    assert train.action_names[7] == "exercise number 7" and len(train.action_names) == 40
    for clip in train.clips + test.clips:
        i = clip.meta["index"]
        assert clip.id == truth["names"][i].removesuffix("_color.avi")
        assert clip.action == int(clip.id.split("_")[0][1:])
        assert clip.motion.num_frames == min(truth["counts"][i], len(truth["world"][i]))
        assert clip.meta["captions_generated"] and clip.meta["source_up_axis"] == "-y"
        _check_canonical(clip)
    np.testing.assert_array_equal(test.rig.offsets, train.rig.offsets)  # the rig is the train split's


def test_uestc_fk_reproduces_vibe_smpl_joints(uestc_root):
    root, truth = uestc_root
    raw = _raw(root / "vibe_cache_refined.pkl")
    vibe_idx, smpl_idx = list(VIBE_TO_SMPL), list(VIBE_TO_SMPL.values())
    worst = 0.0
    for clip in load_uestc(root, "train").clips + load_uestc(root, "test").clips:
        i, n = clip.meta["index"], clip.motion.num_frames
        actor_world = raw["joints3d"][i][:n, vibe_idx] + truth["globtrans"][i][:n, None]  # what ACTOR adds
        expected = place_points(actor_world, clip.meta["placement"])
        worst = max(worst, np.abs(clip.motion.rig_positions()[:, smpl_idx] - expected).max())
        seen = sorted(set(range(24)) - {10, 11, 15, 22, 23})  # bones VIBE's SMPL joints determine
        np.testing.assert_allclose(clip.motion.offsets[seen], truth["offsets"][i][seen], atol=1e-4)
        unseen = np.linalg.norm(
            clip.motion.offsets[[10, 11, 15, 22, 23]] - truth["offsets"][i][[10, 11, 15, 22, 23]], axis=-1
        )
        assert unseen.max() < 0.03  # template, scaled to the performer
    assert worst <= FK_TOLERANCE


def test_uestc_skips_videos_without_estimates(tmp_path):
    layouts.write_uestc_fixture(tmp_path, num_clips=6, seed=3)
    vibe = _raw(tmp_path / "vibe_cache_refined.pkl")
    for key in vibe:  # VIBE found nobody in test video 4: ACTOR's file keeps empty entries
        vibe[key][4] = np.zeros((0,))
    with open(tmp_path / "vibe_cache_refined.pkl", "wb") as f:
        pickle.dump(vibe, f)
    assert [c.meta["index"] for c in load_uestc(tmp_path, "test").clips] == []
    assert len(load_uestc(tmp_path, "train").clips) == 3


def test_uestc_uses_actors_translation_cache_when_present(tmp_path):
    layouts.write_uestc_fixture(tmp_path / "a", num_clips=6, seed=2)
    layouts.write_uestc_fixture(tmp_path / "b", num_clips=6, seed=2, globtrans_cache=True)
    a, b = load_uestc(tmp_path / "a", "train"), load_uestc(tmp_path / "b", "train")
    for ca, cb in zip(a.clips, b.clips, strict=True):
        np.testing.assert_allclose(ca.motion.root, cb.motion.root, atol=1e-5)


@pytest.mark.parametrize("dataset", ["humanact12", "uestc"])
def test_missing_files_name_path_and_layout(tmp_path, dataset):
    load, write = (load_humanact12, layouts.write_humanact12_fixture) if dataset == "humanact12" else (
        load_uestc, layouts.write_uestc_fixture)  # fmt: skip
    with pytest.raises(DatasetNotFoundError) as err:
        load(tmp_path / "nowhere", "train")
    assert str(tmp_path / "nowhere") in str(err.value) and "Expected layout" in str(err.value)
    write(tmp_path / "d", num_clips=4)
    missing = tmp_path / "d" / ("humanact12poses.pkl" if dataset == "humanact12" else "info/num_frames_min.txt")
    missing.unlink()
    with pytest.raises(DatasetNotFoundError) as err:
        load(tmp_path / "d", "train")
    message = str(err.value)
    assert str(missing) in message and ("joints3D" in message or "joints3d" in message)
    assert "download_datasets.sh" in message


class _RunsCode:
    def __init__(self, marker: Path):
        self.marker = marker

    def __reduce__(self):
        return (os.system, (f"touch {self.marker}",))


def test_safe_pickle_refuses_code(tmp_path):
    marker = tmp_path / "pwned"
    path = tmp_path / "humanact12poses.pkl"
    with open(path, "wb") as f:
        pickle.dump({"poses": [_RunsCode(marker)], "joints3D": [], "y": []}, f)
    with pytest.raises(pickle.UnpicklingError, match="system is not allowed"):
        load_pickle(path)
    with pytest.raises(pickle.UnpicklingError, match=str(path)):
        load_humanact12(tmp_path, "train")
    assert not marker.exists()
    arrays = {"a": [np.arange(6.0).reshape(2, 3), np.float32(2.5)], "b": (1, "x"), "c": {3}}
    for protocol in (2, 4, 5):
        with open(path, "wb") as f:
            pickle.dump(arrays, f, protocol=protocol)
        loaded = load_pickle(path)
        np.testing.assert_array_equal(loaded["a"][0], arrays["a"][0])
        assert loaded["b"] == (1, "x") and loaded["c"] == {3} and loaded["a"][1] == np.float32(2.5)


def test_wrong_structure_is_one_clear_error(tmp_path):
    layouts.write_humanact12_fixture(tmp_path, num_clips=3)
    data = _raw(tmp_path / "humanact12poses.pkl")
    broken = {k: v for k, v in data.items() if k != "joints3D"}
    with open(tmp_path / "humanact12poses.pkl", "wb") as f:
        pickle.dump(broken, f)
    with pytest.raises(ValueError, match="'joints3D' missing"):
        load_humanact12(tmp_path, "train")
    data["poses"][1] = data["poses"][1][:, :69]
    with open(tmp_path / "humanact12poses.pkl", "wb") as f:
        pickle.dump(data, f)
    with pytest.raises(ValueError, match=r"poses\[1\] has shape \(\d+, 69\), expected \(N, 72\)"):
        load_humanact12(tmp_path, "train")
    layouts.write_uestc_fixture(tmp_path / "u", num_clips=4)
    vibe = _raw(tmp_path / "u" / "vibe_cache_refined.pkl")
    vibe["joints3d"][2] = vibe["joints3d"][2][:, :24]
    with open(tmp_path / "u" / "vibe_cache_refined.pkl", "wb") as f:
        pickle.dump(vibe, f)
    with pytest.raises(ValueError, match=r"joints3d\[2\] has shape \(\d+, 24, 3\), expected \(\d+, 49, 3\)"):
        load_uestc(tmp_path / "u", "test")


def test_unnormalised_action_data_for_the_mdm_presets(humanact12_root):
    """normalise=False (MDM's a2m presets): the model sees the features as they are (mean 0, std 1)."""
    from motiondiff.data.action_datamodules import HumanAct12DataModule

    root, _ = humanact12_root
    raw, normed = (HumanAct12DataModule(root, batch_size=4, normalise=flag) for flag in (False, True))
    raw.setup("fit")
    normed.setup("fit")
    assert np.array_equal(raw.mean, np.zeros_like(normed.mean)) and np.array_equal(raw.std, np.ones_like(normed.std))
    assert not np.allclose(normed.std, 1.0)  # the default does normalise
