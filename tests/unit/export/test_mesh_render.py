"""render=mesh: a motion's SMPL body mesh (export.smpl_mesh) and its shaded video (export.mesh_render), with a
synthetic body model of the real layout (the real one is licence-restricted).

In the synthetic model every joint owns a cloud of vertices centred on it, skinned 0.8 to the joint and 0.2 to its
parent; linear blend skinning then moves the cloud's mean exactly to where forward kinematics puts the joint (the
parent's transform takes the joint's rest position to the same place), so without pose correctives the posed clouds
are the joints of the SMPL parameters, and those are the motion's joints to the IK's fit."""

from __future__ import annotations

import numpy as np
import pytest
from fixtures.synthetic_smpl import PER_JOINT, write_synthetic_smpl
from PIL import Image

from motiondiff.data.datamodules import embedded_data_root
from motiondiff.data.formats.prepared import load_split
from motiondiff.data.formats.smpl_params import SmplBody, load_smpl_body
from motiondiff.data.representations import get_representation
from motiondiff.export import smpl_joints
from motiondiff.export.mesh_render import render_mesh
from motiondiff.export.outputs import check_formats_for
from motiondiff.export.smpl_export import smpl_parameters
from motiondiff.export.smpl_mesh import render_body, smpl_vertices
from motiondiff.geometry.skeleton import KIT21, SMPL22, SMPL24
from motiondiff.pipelines import MotionOutput
from motiondiff.runtime.errors import UsageError

FPS = 20.0


@pytest.fixture(scope="module")
def clip():
    return load_split(embedded_data_root(), "val").clips()[0].joints.astype(np.float64)  # SMPL-22, 20 fps


@pytest.fixture(scope="module")
def params(clip):
    data, distance, method = smpl_parameters(clip, SMPL22, FPS)
    assert method == "ik" and distance.max() < 1e-5  # a real clip's bones are rigid: IK is exact
    return data


def cloud_means(vertices: np.ndarray, joints: int) -> np.ndarray:
    return vertices.reshape(len(vertices), joints, -1, 3).mean(axis=2)


@pytest.mark.parametrize("pelvis_shift", [0.0, 0.12])
def test_the_posed_clouds_are_the_motions_joints(tmp_path, clip, params, pelvis_shift):
    # the model's rest skeleton is the one IK solved on; a model whose rest pelvis sits elsewhere still walks on the
    # motion's root
    rest = params["rest_joints"] + [0.0, pelvis_shift, 0.0]
    body = load_smpl_body(write_synthetic_smpl(tmp_path / "model.npz", rest_joints=rest))
    plain = SmplBody(body.v_template, body.shapedirs, body.J_regressor, body.parents, body.weights, body.faces)
    means = cloud_means(smpl_vertices(clip, SMPL22, FPS, plain), 24)
    expected = smpl_joints(params)
    np.testing.assert_allclose(means, expected, atol=1e-9)  # the hands (22, 23) at rest on the wrists
    assert np.linalg.norm(means[:, :22] - clip, axis=-1).max() < 1e-5
    # with the model's pose correctives (small random ones in the synthetic model) the clouds move a little
    corrected = cloud_means(smpl_vertices(clip, SMPL22, FPS, body), 24)
    assert 1e-4 < np.linalg.norm(corrected - expected, axis=-1).max() < 0.015


def smplh_like(tmp_path, rest: np.ndarray) -> SmplBody:
    """A 52-joint body of the SMPL+H layout: SMPL's 22 body joints, then 15 joints on each wrist (the fingers)."""
    base = load_smpl_body(write_synthetic_smpl(tmp_path / "base.npz", rest_joints=rest))
    parents = np.array(list(SMPL24.parents[:22]) + [20] * 15 + [21] * 15)
    clouds = base.v_template.reshape(24, PER_JOINT, 3)[:22] - rest[:22, None]
    along = np.linspace(0.03, 0.1, 15)[:, None]
    fingers = rest[parents[22:]] + np.concatenate([along * [1.0, -0.2, 0.1], along * [-1.0, -0.2, 0.1]])
    v = np.concatenate([rest[:22, None] + clouds, fingers[:, None] + 0.3 * clouds[:1]]).reshape(-1, 3)
    owner = np.repeat(np.arange(52), PER_JOINT)
    regressor = np.zeros((52, len(v)))
    regressor[owner, np.arange(len(v))] = 1 / PER_JOINT
    weights = np.zeros((len(v), 52))
    weights[np.arange(len(v)), owner] = 0.8
    weights[np.arange(len(v)), np.maximum(parents[owner], 0)] += 0.2
    faces = np.arange(len(v)).reshape(-1, 3)
    return SmplBody(v, np.zeros((len(v), 3, 10)), regressor, parents, weights, faces)


def test_an_smplh_model_poses_its_body_and_keeps_its_fingers_at_rest(tmp_path, clip, params):
    body = smplh_like(tmp_path, params["rest_joints"])
    means = cloud_means(smpl_vertices(clip, SMPL22, FPS, body), 52)
    np.testing.assert_allclose(means[:, :22], smpl_joints(params)[:, :22], atol=1e-9)
    rest = body.rest_joints()
    wrists = np.array(body.parents[22:])
    reach = np.linalg.norm(means[:, 22:] - means[:, wrists], axis=-1)  # each finger rigid on its wrist
    np.testing.assert_allclose(reach, np.linalg.norm(rest[22:] - rest[wrists], axis=-1)[None].repeat(len(clip), 0))


def body_pixels(frame: Image.Image) -> np.ndarray:
    """The mesh's pixels: gray and darker than the ground grid (#dddddd) and the white background."""
    rgb = np.asarray(frame.convert("RGB")).astype(float) / 255
    return (rgb.max(-1) < 0.8) & (rgb.max(-1) - rgb.min(-1) < 0.06)


def test_the_video_shows_a_shaded_body_framed_like_the_stick_figure(tmp_path, clip, params):
    body = load_smpl_body(write_synthetic_smpl(tmp_path / "beads.npz", rest_joints=params["rest_joints"],
                                               sphere=(6, 8)))  # fmt: skip
    vertices = smpl_vertices(clip[:20], SMPL22, FPS, body)
    path = render_mesh(vertices, body.faces, tmp_path / "walk.gif", "", FPS, joints=clip[:20], skeleton=SMPL22)
    video = Image.open(path)
    assert video.n_frames == 20
    for k in (0, 19):
        video.seek(k)
        mask = body_pixels(video)
        rows, cols = np.where(mask.any(1))[0], np.where(mask.any(0))[0]
        assert 0.02 < mask.mean() < 0.3  # a body, not a blank frame nor a filled one
        assert (rows[-1] - rows[0]) / mask.shape[0] > 0.55  # tall in the frame, as the stick figure
        assert abs((cols[0] + cols[-1]) / 2 / mask.shape[1] - 0.5) < 0.15  # the camera follows it
        gray = np.asarray(video.convert("L"))[mask]
        assert gray.std() > 10  # shaded: faces turned to the light are brighter
    # meshes alone: the camera follows their centroid
    alone = Image.open(render_mesh(vertices[:3], body.faces, tmp_path / "alone.gif"))
    mask = body_pixels(alone)
    cols = np.where(mask.any(0))[0]
    assert (
        alone.n_frames == 3 and 0.02 < mask.mean() < 0.3 and abs((cols[0] + cols[-1]) / 2 / mask.shape[1] - 0.5) < 0.15
    )


def test_bad_meshes_are_refused_before_a_file_is_written(tmp_path):
    vertices = np.zeros((3, 4, 3))
    with pytest.raises(ValueError, match=r"faces index vertices 0..3, got 0..4"):
        render_mesh(vertices, np.array([[0, 1, 4]]), tmp_path / "x.gif")
    with pytest.raises(ValueError, match=r"vertices must be finite"):
        render_mesh(np.full((3, 4, 3), np.nan), np.array([[0, 1, 2]]), tmp_path / "x.gif")
    with pytest.raises(ValueError, match=r"use a .mp4 or .gif"):
        render_mesh(vertices, np.array([[0, 1, 2]]), tmp_path / "x.png")
    assert not list(tmp_path.iterdir())


def write_model(tmp_path, **change) -> str:
    path = write_synthetic_smpl(tmp_path / "model.npz")
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    arrays.update(change)
    np.savez(path, **{k: v for k, v in arrays.items() if v is not None})
    return str(path)


def test_render_body_choices(tmp_path):
    assert render_body("stick", None) is None and render_body(None, None) is None
    body = render_body(" Mesh ", write_model(tmp_path))
    assert body is not None and body.faces.shape == (48, 3)


@pytest.mark.parametrize(
    "render, model, message",
    [
        ("cube", None, r"unknown render='cube': choose stick .* or mesh"),
        ("mesh", None, r"licence-restricted .*smpl\.is\.tue\.mpg\.de.* pass smpl_model="),
        ("mesh", "nowhere.npz", r"smpl_model=nowhere.npz not found"),
        ("mesh", "SMPL_NEUTRAL.pkl", r"\.pkl holds chumpy objects"),
        ("stick", "model.npz", r"is the body of render=mesh videos: add render=mesh"),
        ("mesh", {"f": None}, r"no skinning weights or faces"),
        ("mesh", {"f": np.array([[0, 1, 999]])}, r"faces index vertices up to 999, but it has 144"),
        ("mesh", {"kintree_table": np.stack([[2**32 - 1, *range(23)], range(24)])}, r"not SMPL's body joints"),
    ],
)
def test_render_body_refusals_name_the_fix(tmp_path, render, model, message):
    model = write_model(tmp_path, **model) if isinstance(model, dict) else model
    if model == "model.npz":
        model = write_model(tmp_path)
    with pytest.raises(UsageError, match=message) as caught:
        render_body(render, model)
    assert "\n" not in str(caught.value)


def test_mesh_videos_need_a_smpl_skeleton_and_a_video(tmp_path):
    body = render_body("mesh", write_model(tmp_path))
    check_formats_for(["gif", "bvh"], SMPL22, body=body)
    with pytest.raises(UsageError, match=r"render=mesh needs a motion on SMPL-22 .*'kit21'.*use render=stick"):
        check_formats_for(["mp4"], KIT21, body=body)
    with pytest.raises(UsageError, match=r"export=bvh has none: add mp4 or gif to export="):
        check_formats_for(["bvh"], SMPL22, body=body)
    rep = get_representation("kit251", KIT21)
    kit = np.zeros((4, 21, 3))
    output = MotionOutput([kit], [np.zeros((4, rep.dim))], [None], 12.5, KIT21, rep)
    with pytest.raises(UsageError, match="render=mesh needs a motion on SMPL-22"):
        output.save(tmp_path / "out", formats=["mp4"], render="mesh", smpl_model=write_model(tmp_path))
    assert not (tmp_path / "out").exists()
