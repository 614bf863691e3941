"""edit.py end to end on a tiny trained model: in-betweening and body-part editing of a dataset clip, a BVH file and
a joints .npy; the kept part is the input's (checked from the files written), bad input gets one clear line; and the
acceptance run (python -m motiondiff.studies.editing) runs with small numbers."""

from __future__ import annotations

import json
import zipfile

import numpy as np
import pytest
from cli_helpers import REPO, run_cli
from hydra import compose, initialize_config_dir
from PIL import Image

from motiondiff.cli.common import UsageError, register_resolvers
from motiondiff.data.datamodules import embedded_data_root
from motiondiff.data.formats.bvh import motion_from_arrays, write_bvh
from motiondiff.data.formats.prepared import load_split
from motiondiff.data.representations.hml_features import joints_from_features
from motiondiff.geometry.skeleton import SMPL22

register_resolvers()
CLIP_ID = "dataset-1_walk_active_001"
FAST = ["sampler=ddim", "steps=5", "num_samples=2", "export=none"]
TOL = 1e-4  # metres


@pytest.fixture(scope="module")
def clip():
    """The test clip's arrays: canonical SMPL-22 joints, native rotations/root/offsets, its hml263 features."""
    data = load_split(embedded_data_root(), "test")
    i = [str(c) for c in data.arrays["ids"]].index(CLIP_ID)
    s, a = data.clip_slice(i), data.arrays
    return {"joints": a["joints"][s], "rotations": a["native_rotations"][s], "root": a["native_root"][s],
            "offsets": a["native_offsets"][i], "names": [str(n) for n in a["native_joint_names"]],
            "parents": a["native_parents"], "features": a["features"][data.feature_slice(i)]}  # fmt: skip


@pytest.fixture(scope="module")
def bvh_of_clip(clip, tmp_path_factory):
    """The embedded clip written back as a Bandai-style BVH (centimetres, the rig's joint names)."""
    motion = motion_from_arrays(clip["names"], clip["parents"], clip["offsets"] * 100, clip["rotations"],
                                clip["root"] * 100, fps=20.0)  # fmt: skip
    return write_bvh(tmp_path_factory.mktemp("bvh") / f"{CLIP_ID}.bvh", motion)


def _edit(tmp_path, ckpt, *overrides):
    run_cli("edit.py", f"checkpoint={ckpt}", *FAST, *overrides, env_dir=tmp_path)
    out = next((tmp_path / "outputs" / "edit").iterdir())
    return out, json.loads((out / "results.json").read_text())


def _max_error(a, b, frames=slice(None), joints=slice(None)) -> float:
    return float(np.linalg.norm(a[frames][:, joints] - b[frames][:, joints], axis=-1).max())


def test_inbetween_a_dataset_clip(text_ckpt, tmp_path, clip):
    out, res = _edit(tmp_path, text_ckpt, f"input=test:{CLIP_ID}", "kind=inbetween", "text=a person jumps",
                     "prefix=0.25", "suffix=10")  # fmt: skip
    p, s = res["settings"]["prefix_frames"][0], res["settings"]["suffix_frames"][0]
    assert (p, s) == (20, 10) and res["input"]["split"] == "test" and res["condition"] == "a person jumps"
    for row in res["samples"]:
        joints, inputs = np.load(row["joints"]), np.load(row["input_joints"])
        assert joints.shape == inputs.shape == (79, 22, 3) and np.load(row["features"]).shape == (79, 263)
        assert np.allclose(inputs, joints_from_features(clip["features"]), atol=1e-5)  # the clip, as the model sees it
        assert _max_error(joints, inputs, slice(0, p)) <= TOL and _max_error(joints, inputs, slice(79 - s, 79)) <= TOL
        assert _max_error(joints, inputs, slice(p, 79 - s)) > 1e-2  # the middle is generated
        assert row["kept_max_error_m"] <= TOL and [b["side"] for b in row["boundaries"]] == ["start", "end"]


def test_inbetween_a_bvh_file_prepared_like_the_dataset(text_ckpt, tmp_path, clip, bvh_of_clip):
    out, res = _edit(tmp_path, text_ckpt, f"input={bvh_of_clip}", "kind=inbetween", "prefix_s=0.5", "suffix_s=1",
                     "mode=repaint", "num_samples=1")  # fmt: skip
    row = res["samples"][0]
    joints, inputs = np.load(row["joints"]), np.load(row["input_joints"])
    assert res["condition"] is None and res["settings"]["guidance"] is None  # unconditioned on a text model
    assert np.abs(inputs - joints_from_features(clip["features"])).max() <= TOL  # same preparation as the dataset
    assert _max_error(joints, inputs, slice(0, 10)) <= TOL and _max_error(joints, inputs, slice(59, 79)) <= TOL


def test_inbetween_a_long_shared_bandai_bvh(text_ckpt, tmp_path, shared):
    """A real Bandai file (longer than the model's 4 s): the first window the model can take is edited."""
    with zipfile.ZipFile(shared("data", "bandai-namco", "bandai-ds1.zip")) as z:
        path = tmp_path / "walk.bvh"
        path.write_bytes(z.read(f"data/{CLIP_ID}.bvh"))
    out, res = _edit(tmp_path, text_ckpt, f"input={path}", "kind=inbetween", "text=a person walks", "num_samples=1")
    assert res["input"]["window"] == [0, 81] and res["input"]["total_frames"] > 81
    assert res["samples"][0]["kept_max_error_m"] <= TOL


def test_body_part_editing_regenerates_the_upper_body_as_the_api_does(text_ckpt, tmp_path):
    """parts= names the regenerated parts on the command line as in `MotionPipeline.edit_parts`: both keep the same
    joints of the input, exactly."""
    from motiondiff.pipelines import MotionPipeline

    out, res = _edit(tmp_path, text_ckpt, f"input={CLIP_ID}", "kind=parts", "parts=upper_body", "mode=repaint",
                     "text=a person raises both hands", "clip_x0=static")  # fmt: skip
    assert res["settings"]["clip_x0"] == "static"  # safe x̂0 is a switch of edit.py too
    lower, upper = list(SMPL22.parts["lower_body"]), list(SMPL22.parts["upper_body"])
    assert res["settings"]["kept_joints"] == [SMPL22.joint_names[j] for j in lower]
    assert res["settings"]["regenerated_joints"] == [SMPL22.joint_names[j] for j in upper]
    api = MotionPipeline.from_pretrained(text_ckpt).edit_parts(CLIP_ID, "a person raises both hands",
                                                               parts="upper_body", steps=2, mode="repaint")  # fmt: skip
    assert api.info["kept_joints"] == res["settings"]["kept_joints"]
    cli_joints = np.load(res["samples"][0]["joints"])
    n = min(len(cli_joints), len(api.joints[0]))
    assert _max_error(cli_joints[:n], api.joints[0][:n], joints=lower) <= 1e-6
    for row in res["samples"]:
        joints, inputs = np.load(row["joints"]), np.load(row["input_joints"])
        rel, rel_in = joints - joints[:, :1], inputs - inputs[:, :1]
        assert _max_error(joints, inputs, joints=lower) <= TOL and _max_error(rel, rel_in, joints=lower) <= TOL
        assert _max_error(joints, inputs, joints=upper) > 1e-2
        assert row["root_relative_kept_max_error_m"] <= TOL


def test_joints_npy_input_a_window_and_videos(text_ckpt, tmp_path, clip):
    npy = tmp_path / "walk_joints.npy"
    np.save(npy, clip["joints"])
    out, res = _edit(tmp_path, text_ckpt, f"input={npy}", "kind=parts", "parts=[torso,arms,head]",
                     "length=1", "num_samples=1", "export=gif", "video.size=160")  # fmt: skip
    row = res["samples"][0]
    inputs = np.load(row["input_joints"])
    assert res["input"]["window"] == [0, 21] and inputs.shape == (20, 22, 3)  # 1 s = 20 edited frames
    # the window is canonicalised on its own, as `prepare` does (the facing is smoothed over fewer frames: mm apart)
    assert np.abs(inputs - joints_from_features(clip["features"])[:20]).max() <= 1e-2
    assert row["kept_max_error_m"] <= TOL
    assert (out / "input.gif").stat().st_size > 1000 and row["video"].endswith(".gif")
    assert Image.open(row["video"]).size == (160, 160)  # video.size=


# ---- bad input: one clear line ------------------------------------------------------------------------------------
def _run_in_process(ckpt, *overrides):
    from motiondiff.cli.edit import run

    with initialize_config_dir(config_dir=str(REPO / "conf"), version_base="1.3"):
        cfg = compose("edit", overrides=[f"checkpoint={ckpt}", *FAST, *overrides])
    return run(cfg)


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ([], "pass the motion to edit"),
        (["input=nowhere/walk.bvh"], "nowhere/walk.bvh not found"),
        (["input=test:no_such_clip"], "no clip 'no_such_clip' in the test split"),
        (["input=sideways:" + CLIP_ID], "unknown split 'sideways'"),
        ([f"input={CLIP_ID}", "kind=parts", "parts=tail"], "unknown body part 'tail'.*presets: arms, head, left_arm"),
        ([f"input={CLIP_ID}", "prefix=0.5", "suffix=0.5"], "nothing to generate"),
        ([f"input={CLIP_ID}", "prefix=2.5"], "prefix_s"),
        ([f"input={CLIP_ID}", "kind=dance"], "unknown kind 'dance'"),
        ([f"input={CLIP_ID}", "mode=paint"], "overwrite, repaint"),
        ([f"input={CLIP_ID}", "hold_from=0"], r"hold_from=.* in \(0, 1\]"),
        ([f"input={CLIP_ID}", "hold_from=half"], r"hold_from=.* in \(0, 1\]"),
        ([f"input={CLIP_ID}", "reconstruction=-2"], "reconstruction=.* >= 0"),
        ([f"input={CLIP_ID}", "action=walk"], "use text="),
        ([f"input={CLIP_ID}", "length=10"], "longer than this model's maximum of 80"),
    ],
)
def test_bad_input_is_a_usage_error(text_ckpt, overrides, message):
    with pytest.raises(UsageError, match=message):
        _run_in_process(text_ckpt, *overrides)


def test_npy_with_the_wrong_joint_count(text_ckpt, tmp_path):
    npy = tmp_path / "kit.npy"
    np.save(npy, np.zeros((30, 21, 3), np.float32))
    with pytest.raises(UsageError, match=r"shape \(30, 21, 3\).*\(frames, 22, 3\) joints of its smpl22 skeleton"):
        _run_in_process(text_ckpt, f"input={npy}")


def test_cli_prints_one_line_and_exits_2(text_ckpt, tmp_path):
    proc = run_cli("edit.py", f"checkpoint={text_ckpt}", f"input={CLIP_ID}", "kind=parts", "parts=tail", process=True,
                   env_dir=tmp_path, check=False)  # fmt: skip
    assert proc.returncode == 2 and proc.stderr.strip().startswith("error: unknown body part 'tail'")
    assert "Traceback" not in proc.stderr


# ---- the acceptance measurements ----------------------------------------------------------------------------------
@pytest.mark.parametrize("bad", ["hold_from=abc", "reconstruction=lots", "steps=many"])
def test_editing_evaluation_names_a_bad_number(text_ckpt, bad):
    from motiondiff.studies.editing import main

    with pytest.raises(UsageError, match=bad.split("=")[0] + ".*number"):
        main([f"checkpoint={text_ckpt}", bad])


def test_editing_evaluation_runs(text_ckpt, tmp_path):
    from motiondiff.studies.editing import main

    out = main([f"checkpoint={text_ckpt}", "num_edits=3", "num_part_edits=2", "steps=3", "hold_from=0.5",
                "reconstruction=2", f"out={tmp_path}"])  # fmt: skip
    report = json.loads((out / "report.json").read_text())
    assert report["sampling"]["hold_from"] == 0.5 and "held at t < 0.5·T" in (out / "report.md").read_text()
    text = (out / "report.md").read_text()
    assert report["sampling"]["reconstruction"] == 2.0 and "reconstruction guidance 2" in text
    assert all(0 < r["inbetween"]["median_smoothness"] <= 1 for r in report["modes"].values())
    assert 0 <= report["inputs_change_ratio"]["share_le_3"] <= 1 and "Max change ratio" in text
    assert 0 < report["inputs_median_smoothness"] <= 1
    assert set(report["modes"]) == {"overwrite", "repaint"} and "| repaint |" in (out / "report.md").read_text()
    assert all("walk" in c for c in report["parts_clips"]) and len(report["inbetween_clips"]) == 3
    low = report["low_noise"]
    assert low["clips"] == 3 and 0 < low["x_t_mpjpe_m"] < 0.05 and low["x0_hat_mpjpe_m"] > 0
    assert "Denoiser at t = 20" in (out / "report.md").read_text()
    for r in report["modes"].values():
        assert r["inbetween"]["max_kept_error_m"] <= TOL and r["parts"]["max_root_relative_kept_error_m"] <= TOL
        assert 0.0 <= r["inbetween"]["share_ratio_le_3"] <= 1.0 and r["parts"]["edits"] == 2
        assert 0 < r["parts"]["median_smoothness"] <= 1
        assert len(r["inbetween"]["per_edit"]) == 3 and all(
            len(e["boundaries"]) == 2 for e in r["inbetween"]["per_edit"]
        )
