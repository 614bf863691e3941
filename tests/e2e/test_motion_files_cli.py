"""edit.py on motion files as animation tools write them, with the shipped model: the project's own BVH export of a
real clip, turned to Blender's Z-up, in centimetres at 24 fps, is edited upright with its kept part exact; a file
whose up axis cannot be decided warns and names up_axis=; the edit's own BVH has End Sites of real length and reads
back in bvhio (an independent reader) as the edited joints."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
from fixtures.bvh_reader import bone_lengths, bvhio_positions
from fixtures.in_process import run_entry

from motiondiff.data.datamodules import embedded_data_root
from motiondiff.data.formats.bvh import read_bvh, write_bvh
from motiondiff.data.formats.prepared import load_split
from motiondiff.data.formats.up_axis import UpAxisWarning, rotation_to_y_up
from motiondiff.export import export_bvh
from motiondiff.geometry.rotations import matrix_to_quat, qmul
from motiondiff.geometry.skeleton import SMPL22

CLIP_ID = "dataset-1_walk_active_001"
EDIT = ["checkpoint=shipped", "kind=inbetween", "text=a person walks forward", "steps=10", "num_samples=1", "seed=0"]
HEAD, PELVIS = SMPL22.index("head"), SMPL22.index("pelvis")


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """The clip exported by the project (metres, Y-up, 20 fps), then as Blender would write it (Z-up: offsets, End
    Sites and rotations turned; centimetres; 24 fps), the same in Y-up (the expected reading), and a file whose root
    alone is turned to Z-up (its rest pose still stands along y: the evidence contradicts itself)."""
    folder = tmp_path_factory.mktemp("motion_files")
    data = load_split(embedded_data_root(), "test")
    joints = data.arrays["joints"][data.clip_slice([str(c) for c in data.arrays["ids"]].index(CLIP_ID))]
    exported = read_bvh(export_bvh(folder / "walk.bvh", joints, SMPL22, fps=20.0).path)
    to_z_up = rotation_to_y_up("+z").T
    blender = write_bvh(folder / "walk_blender_z_up_cm_24fps.bvh", exported.rotated(to_z_up).scaled(100).resample(24))
    y_up = write_bvh(folder / "walk_y_up_cm_24fps.bvh", exported.scaled(100).resample(24))
    rotations, translations = exported.rotations.copy(), exported.translations.copy()
    rotations[:, 0] = qmul(np.broadcast_to(matrix_to_quat(to_z_up), rotations[:, 0].shape), rotations[:, 0])
    translations[:, 0] = translations[:, 0] @ to_z_up.T
    turned = write_bvh(
        folder / "walk_root_turned.bvh", replace(exported, rotations=rotations, translations=translations)
    )
    return {"blender": blender, "y_up": y_up, "root_turned": turned}


def _results(out):
    return json.loads((out / "results.json").read_text())


def test_a_blender_z_up_centimetre_24fps_bvh_is_edited_upright_and_exact(files, tmp_path, capsys):
    from motiondiff.edit import load_input_motion
    from motiondiff.pipelines import MotionPipeline

    _, out = run_entry("edit", tmp_path, *EDIT, f"input={files['blender']}", "export=bvh")
    res = _results(out)
    up = res["input"]["up_axis"]
    assert (up["axis"], up["decided"], up["how"]) == ("+z", True, "motion and rest pose")
    assert "up axis of" in capsys.readouterr().out
    row = res["samples"][0]
    joints, inputs = np.load(row["joints"]), np.load(row["input_joints"])
    p, s = res["settings"]["prefix_frames"][0], res["settings"]["suffix_frames"][0]
    n = len(joints)
    # the input is the Y-up file's reading: Z-up, cm and 24 fps converted before the preparation
    expected = load_input_motion(files["y_up"], MotionPipeline.from_pretrained("text").model).joints
    assert inputs.shape == expected.shape and np.abs(inputs - expected).max() <= 1e-5
    kept = np.r_[0:p, n - s : n]
    assert np.abs(joints[kept] - inputs[kept]).max() <= 1e-5 and row["kept_max_error_m"] <= 1e-5
    height = joints[:, HEAD, 1] - joints[:, PELVIS, 1]
    print(f"\nZ-up cm 24 fps BVH -> edit: head above pelvis min {height.min():.3f} m (input "
          f"{(inputs[:, HEAD, 1] - inputs[:, PELVIS, 1]).min():.3f}), kept-part error {row['kept_max_error_m']:.1e} m")  # fmt: skip
    assert height.min() > 0.4
    # the edit's own BVH: End Sites of real length, no zero-length bone, and bvhio reads the edited joints back
    # (up to the fit error the export reports: generated joints stretch bones, a BVH's cannot)
    bvh = row["exports"]["bvh"]
    assert min(bone_lengths(bvh).values()) > 0.01
    again = bvhio_positions(bvh, SMPL22.joint_names)
    assert np.linalg.norm(again - joints, axis=-1).max() <= row["exports"]["bvh_max_error_m"] + 1e-4


def test_a_file_whose_up_axis_cannot_be_decided_warns(files, tmp_path):
    with pytest.warns(UpAxisWarning, match=r"walk_root_turned\.bvh: cannot tell the up axis.*up_axis=y\|z\|x"):
        _, out = run_entry("edit", tmp_path, *EDIT, "steps=2", f"input={files['root_turned']}", "export=none")
    up = _results(out)["input"]["up_axis"]
    assert (up["axis"], up["decided"], up["motion_axis"], up["rest_axis"]) == ("+y", False, "+z", "+y")
    # forcing the axis reads it upright, without a warning
    _, out = run_entry("edit", tmp_path / "forced", *EDIT, "steps=2", f"input={files['root_turned']}", "up_axis=z",
                       "export=none")  # fmt: skip
    res = _results(out)
    inputs = np.load(res["samples"][0]["input_joints"])
    assert res["input"]["up_axis"]["how"] == "forced" and (inputs[:, HEAD, 1] - inputs[:, PELVIS, 1]).min() > 0.4


def amass_like(folder, joints) -> tuple:
    """The clip as an AMASS file would hold it: SMPL parameters of its joints (the project's export=smpl), turned to
    AMASS's Z-up, without the rest offsets (an AMASS file has only poses, trans, betas), at 20 fps; and a synthetic
    SMPL body model whose rest joints are the export's (the real model is licence-restricted)."""
    from fixtures.synthetic_smpl import write_synthetic_smpl
    from scipy.spatial.transform import Rotation

    from motiondiff.export import export_smpl

    report = export_smpl(folder / "walk_smpl.npz", joints, SMPL22, 20.0)
    with np.load(report.path) as f:
        data = {k: f[k] for k in f.files}
    to_z_up = Rotation.from_matrix(rotation_to_y_up("+z").T)
    pelvis = data["rest_joints"][0]
    poses = data["poses"].copy()
    poses[:, :3] = (to_z_up * Rotation.from_rotvec(poses[:, :3])).as_rotvec()
    trans = to_z_up.apply(data["trans"] + pelvis) - pelvis  # the pelvis turned about the origin
    amass = folder / "walk_amass_z_up.npz"
    np.savez(amass, poses=poses, trans=trans, betas=np.zeros(16), gender=np.array("neutral"),
             mocap_framerate=np.array(20.0))  # fmt: skip
    return amass, write_synthetic_smpl(folder / "SMPL_NEUTRAL.npz", rest_joints=data["rest_joints"])


def test_an_amass_smpl_file_is_edited_upright_through_a_body_model(files, tmp_path):
    from fixtures.in_process import user_error

    data = load_split(embedded_data_root(), "test")
    joints = data.arrays["joints"][data.clip_slice([str(c) for c in data.arrays["ids"]].index(CLIP_ID))]
    amass, model = amass_like(tmp_path, joints)
    _, out = run_entry("edit", tmp_path / "run", *EDIT, f"input={amass}", f"smpl_model={model}", "export=none")
    res = _results(out)
    row = res["samples"][0]
    inputs, edited = np.load(row["input_joints"]), np.load(row["joints"])
    assert res["input"]["up_axis"]["axis"] == "+z" and res["input"]["up_axis"]["decided"]
    assert (edited[:, HEAD, 1] - edited[:, PELVIS, 1]).min() > 0.4 and row["kept_max_error_m"] <= 1e-5
    # the same clip read from the y-up project export (which records its skeleton) gives the same input
    from motiondiff.edit import load_input_motion
    from motiondiff.pipelines import MotionPipeline

    expected = load_input_motion(tmp_path / "walk_smpl.npz", MotionPipeline.from_pretrained("text").model).joints
    assert np.abs(inputs - expected).max() <= 1e-4
    message = user_error("edit", tmp_path / "no_model", *EDIT, f"input={amass}")
    assert "holds SMPL parameters (poses, trans, betas) but not the skeleton" in message and "smpl_model=" in message
