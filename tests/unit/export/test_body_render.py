"""render=body: the mannequin's videos (export.body_render), chosen by render=body with no model file, on any
skeleton; MotionOutput.save writes them at the asked size through export.outputs' body route."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from motiondiff.data.datamodules import embedded_data_root
from motiondiff.data.formats.prepared import load_split
from motiondiff.data.representations import get_representation
from motiondiff.export.body_render import MANNEQUIN, mannequin_mesh
from motiondiff.export.outputs import check_formats_for
from motiondiff.export.smpl_mesh import render_body
from motiondiff.geometry.kinematics import forward_kinematics
from motiondiff.geometry.skeleton import KIT21, SMPL22
from motiondiff.pipelines import MotionOutput
from motiondiff.runtime.errors import UsageError


@pytest.fixture(scope="module")
def clip():
    return load_split(embedded_data_root(), "val").clips()[0].joints.astype(np.float64)  # SMPL-22, 20 fps


def body_pixels(frame: Image.Image) -> np.ndarray:
    """The mesh's pixels: gray and darker than the ground grid and the white background."""
    rgb = np.asarray(frame.convert("RGB")).astype(float) / 255
    return (rgb.max(-1) < 0.8) & (rgb.max(-1) - rgb.min(-1) < 0.06)


def test_render_body_is_the_mannequin_and_needs_no_model():
    assert render_body(" Body ", None) is MANNEQUIN
    with pytest.raises(UsageError, match=r"smpl_model=m\.npz is the body of render=mesh videos: .* the mannequin"):
        render_body("body", "m.npz")
    check_formats_for(["mp4", "bvh"], KIT21, body=MANNEQUIN)  # any skeleton
    with pytest.raises(UsageError, match=r"render=body draws the mannequin .* export=bvh has none: add mp4 or gif"):
        check_formats_for(["bvh"], SMPL22, body=MANNEQUIN)


def test_the_mannequin_poses_on_any_skeleton():
    offsets = KIT21.offsets * 0.3
    translations = np.repeat(offsets[None], 3, axis=0)
    rotations = np.tile([1.0, 0.0, 0.0, 0.0], (3, 21, 1))
    joints = forward_kinematics(rotations, translations, KIT21.parents)[0] + np.arange(3)[:, None, None] * 0.1
    vertices, faces = mannequin_mesh(joints, KIT21)
    assert vertices.shape[:2] == (3, faces.max() + 1) and np.isfinite(vertices).all()
    np.testing.assert_allclose(vertices[1] - vertices[0], 0.1, atol=1e-9)  # it moves with the joints


def test_save_writes_mannequin_videos_at_the_asked_size(tmp_path, clip):
    joints = clip[:6].astype(np.float32)
    rep = get_representation("hml263", SMPL22)
    out = MotionOutput([joints], [np.zeros((6, rep.dim))], ["a person walks"], 20.0, SMPL22, rep,
                       {"joints_changed": True})  # fmt: skip
    (row,) = out.save(tmp_path / "out", formats=["gif"], render="body", video_size=128)
    video = Image.open(row["video"])
    assert video.size == (128, 128) and video.n_frames == 6
    for k in (0, 5):
        video.seek(k)
        mask = body_pixels(video)
        rows = np.where(mask.any(1))[0]
        assert 0.02 < mask.mean() < 0.3  # a body, not a blank frame nor a filled one
        assert (rows[-1] - rows[0]) / mask.shape[0] > 0.5  # standing tall in the frame
        assert np.asarray(video.convert("L"))[mask].std() > 8  # shaded
