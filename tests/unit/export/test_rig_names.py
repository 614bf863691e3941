"""Joint-name presets rename the SMPL-22 joints of an exported BVH to a rig's bone names and leave the motion as it
is; another skeleton or an unknown preset is one clear error."""

from __future__ import annotations

import numpy as np
import pytest
from fixtures.synthetic_motion import glide

from motiondiff.data.formats.bvh import read_bvh
from motiondiff.export.bvh_export import export_bvh
from motiondiff.export.rig_names import rig_presets, with_rig_names
from motiondiff.geometry.skeleton import KIT21, SMPL22
from motiondiff.runtime.errors import UsageError


@pytest.mark.parametrize("preset, pelvis, left_wrist", [("smpl", "Pelvis", "L_Wrist"),
                                                        ("mixamo", "mixamorig:Hips", "mixamorig:LeftHand")])  # fmt: skip
def test_presets_rename_the_joints_and_keep_the_motion(tmp_path, preset, pelvis, left_wrist):
    joints = glide(20, 1.0, frames=10)
    plain = read_bvh(export_bvh(tmp_path / "plain.bvh", joints, SMPL22, 20.0).path)
    named = read_bvh(export_bvh(tmp_path / "named.bvh", joints, with_rig_names(SMPL22, preset), 20.0).path)
    renamed = dict(zip(plain.joint_names, named.joint_names, strict=True))  # the file's own joint order
    assert renamed["pelvis"] == pelvis and renamed["l_wrist"] == left_wrist and len(set(named.joint_names)) == 22
    np.testing.assert_array_equal(named.rotations, plain.rotations)
    np.testing.assert_array_equal(named.translations, plain.translations)


def test_other_skeletons_and_unknown_presets_are_clear_errors():
    assert rig_presets() == ["mixamo", "smpl"]
    assert with_rig_names(SMPL22, None) is SMPL22
    with pytest.raises(UsageError, match="this motion is on 'kit21'"):
        with_rig_names(KIT21, "mixamo")
    with pytest.raises(UsageError, match="choose from mixamo, smpl"):
        with_rig_names(SMPL22, "unreal")


def test_sample_py_names_the_bones_of_its_bvh(tmp_path):
    """``bvh_names=mixamo`` through sample.py's config and run; an unknown preset stops before sampling."""
    from fixtures.in_process import run_entry, user_error

    _, out = run_entry("sample", tmp_path, "checkpoint=shipped", "text=a person walks", "num_samples=1", "length=1",
                       "steps=2", "export=[bvh]", "bvh_names=mixamo")  # fmt: skip
    bvh = read_bvh(next(out.glob("*.bvh")))
    assert "mixamorig:Hips" in bvh.joint_names and "mixamorig:LeftHand" in bvh.joint_names
    assert "choose from mixamo, smpl" in user_error("sample", tmp_path / "bad", "checkpoint=shipped", "text=walk",
                                                    "export=[bvh]", "bvh_names=unreal")  # fmt: skip
    assert not list((tmp_path / "bad").rglob("*.npy"))
