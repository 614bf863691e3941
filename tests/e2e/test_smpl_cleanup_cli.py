"""sample.py with export=smpl and cleanup=feet or cleanup=bones, and edit.py with cleanup=feet (in process, the
released text model): the SMPL file of the cleaned joints reproduces them (exactly after cleanup=bones, whose joints
lie on one fixed skeleton; the BVH file too), results.json reports what each clean-up did, and an edit's kept frames
are exactly the model's (and so the input's) after the cleanup."""

from __future__ import annotations

import json

import numpy as np
from fixtures.in_process import run_entry

from motiondiff.export import smpl_joints
from motiondiff.geometry.skeleton import SMPL22

COMMON = ["checkpoint=shipped", "num_samples=1", "cleanup=feet"]


def test_sample_writes_smpl_of_the_cleaned_joints(tmp_path):
    _, out = run_entry("sample", tmp_path, *COMMON, "export=[smpl]", "text=a person walks forward", "length=3")
    row = json.loads((out / "results.json").read_text())["samples"][0]
    joints, raw = np.load(row["joints"]), np.load(row["joints"].replace("_joints.npy", "_joints_raw.npy"))
    feet = row["foot_cleanup"]
    assert feet["sliding_after_cm_s"] < feet["sliding_before_cm_s"] and not np.array_equal(joints, raw)
    with np.load(row["exports"]["smpl"]) as data:
        error = np.linalg.norm(smpl_joints(data)[:, :22] - joints, axis=-1).max()
    # the fit error results.json reports is the file's (the acceptance bound is in unit/export/test_export_smpl.py;
    # this 3 s walk stretches its bones more: 2.5 cm)
    assert abs(error - row["exports"]["smpl_max_error_m"]) < 1e-5 and error < 0.05
    assert row["exports"]["smpl_method"] == "ik"  # solved from the cleaned joints, not the model's features


def test_bone_cleanup_makes_every_file_agree_with_the_joints(tmp_path):
    _, out = run_entry("sample", tmp_path, "checkpoint=shipped", "num_samples=1", "cleanup=[feet,bones]",
                       "export=[smpl,bvh]", "text=a person walks forward", "length=3")  # fmt: skip
    row = json.loads((out / "results.json").read_text())["samples"][0]
    joints, raw = np.load(row["joints"]), np.load(row["joints"].replace("_joints.npy", "_joints_raw.npy"))
    bones, feet = row["bones"], row["foot_cleanup"]
    moved = np.linalg.norm(joints - raw, axis=-1).max()
    assert bones["bound_m"] <= bones["max_move_m"] < 0.05 and moved <= bones["max_move_m"] + feet["max_shift_m"] + 1e-6
    assert feet["sliding_after_cm_s"] < feet["sliding_before_cm_s"]  # bones ran first, then feet kept lengths
    parents = np.array(SMPL22.parents)
    lengths = np.linalg.norm(joints[:, 1:] - joints[:, parents[1:]], axis=-1)
    assert (lengths.max(0) - lengths.min(0)).max() < 1e-4  # one fixed skeleton (float32 files)
    with np.load(row["exports"]["smpl"]) as data:
        assert np.linalg.norm(smpl_joints(data)[:, :22] - joints, axis=-1).max() < 1e-4
    assert row["exports"]["bvh_max_error_m"] < 1e-4


def test_edit_cleanup_leaves_kept_frames_exactly(tmp_path):
    _, out = run_entry("edit", tmp_path, *COMMON, "steps=5", "export=none", "input=test:dataset-1_walk_active_001",
                       "kind=inbetween", "text=a person walks forward")  # fmt: skip
    row = json.loads((out / "results.json").read_text())["samples"][0]
    kept = np.load(out / "keep_mask.npy").all(axis=1)  # frames whose every feature came from the input
    joints, raw = np.load(row["joints"]), np.load(row["joints"].replace("_joints.npy", "_joints_raw.npy"))
    assert 0 < kept.sum() < len(kept) and "foot_cleanup" in row
    np.testing.assert_array_equal(joints[kept], raw[kept])
    assert np.abs(joints[kept] - np.load(row["input_joints"])[kept]).max() <= max(row["kept_max_error_m"], 1e-6)
