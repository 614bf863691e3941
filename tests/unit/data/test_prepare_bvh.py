"""The generic `bvh` prepare source on synthetic CMU-style files (centimetres, CMU's zero-offset joints) in two
sub-folders with a labels file; the joint-map guess on the conventions it reads and on a real Bandai skeleton."""

from __future__ import annotations

import json
import shutil
import zipfile

import numpy as np
import pytest
from test_bvh import CMU_NAMES, CMU_PARENTS, Spec, bvh_text, reference_positions

from motiondiff.data.formats.joint_map import JointMap
from motiondiff.data.formats.prepared import load_split
from motiondiff.data.preparing import writer
from motiondiff.data.preparing.from_bvh import ensure_prepared_bvh, path_labels, prepare_bvh
from motiondiff.data.preparing.prepare import PrepareError, main
from motiondiff.data.preparing.processing import TARGET_FPS

LEFT = {"LHipJoint": [0, 0, 0], "LeftUpLeg": [9, -5, 0], "LeftLeg": [0, -42, 0], "LeftFoot": [0, -40, 0],
        "LeftToeBase": [0, -6, 12], "LeftShoulder": [0, 0, 0], "LeftArm": [16, 6, 0], "LeftForeArm": [27, 0, 0],
        "LeftHand": [25, 0, 0], "LeftFingerBase": [5, 0, 0], "LeftHandIndex1": [3, 0, 0], "LThumb": [2, 0, 3]}  # fmt: skip
MIDDLE = {"Hips": [0, 95, 0], "LowerBack": [0, 0, 0], "Spine": [0, 12, 0], "Spine1": [0, 12, 0], "Neck": [0, 0, 0],
          "Neck1": [0, 16, 0], "Head": [0, 10, 0]}  # fmt: skip
ZYX = ("Zrotation", "Yrotation", "Xrotation")


def human_spec(names=CMU_NAMES, parents=CMU_PARENTS) -> Spec:
    """A CMU skeleton with human proportions in centimetres (legs 82 cm), facing +Z with its left at +X."""
    offsets = []
    for n in names:
        if n in MIDDLE:
            offsets.append(MIDDLE[n])
        else:
            left = n.replace("Right", "Left").replace("RHip", "LHip").replace("RThumb", "LThumb")
            offsets.append(np.array(LEFT[left]) * ([-1, 1, 1] if left != n else 1))
    channels = [("Xposition", "Yposition", "Zposition", *ZYX) if p < 0 else ZYX for p in parents]
    return Spec(list(names), list(parents), np.array(offsets, dtype=float), channels, {})


def walk_values(spec: Spec, frames: int, seed: int) -> np.ndarray:
    """Root walking forward ~1 m/s at 60 fps, every joint swinging up to 25 degrees."""
    rng = np.random.default_rng(seed)
    t = np.arange(frames)[:, None] / 60.0
    cols = [np.zeros(frames), 95 + 2 * np.sin(6 * t[:, 0]), 100 * t[:, 0]]
    for _ in range(3 * len(spec.names)):
        cols.append(25 * np.sin(2 * np.pi * rng.uniform(0.5, 2) * t[:, 0] + rng.uniform(0, 6)))
    return np.stack(cols, axis=1)


def write_bvh(path, seed, spec=None, frames=90):
    spec = spec or human_spec()
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(bvh_text(spec, walk_values(spec, frames, seed), 1 / 60))


@pytest.fixture(scope="module")
def mocap(tmp_path_factory):
    """12 good files in walk/ and jump/, one with another skeleton, one truncated, and a labels file."""
    root = tmp_path_factory.mktemp("bvh") / "mocap"
    for i in range(6):
        write_bvh(root / "walk" / f"w{i}.bvh", seed=i)
        write_bvh(root / "jump" / f"j{i}.bvh", seed=10 + i)
    write_bvh(root / "jump" / "thumbless.bvh", 20, human_spec(CMU_NAMES[:-1], CMU_PARENTS[:-1]))
    text = (root / "walk" / "w0.bvh").read_text()
    (root / "walk" / "cut.bvh").write_text(text[: len(text) // 2])
    labels = root.parent / "labels.csv"
    labels.write_text(
        "file,action,style,caption\n"
        "walk/w0.bvh,,happy,a person strolls forward.|someone walks ahead happily.\n"
        "j1.bvh,hop,,\n"
        "walk/w2.bvh,,,a person walks.\n"
    )
    out = root.parent / "prepared"
    report = prepare_bvh([root], out, labels, workers=1, progress=False)
    return root, labels, out, report


def all_clips(out):
    return {s: load_split(out, s) for s in ("train", "val", "test")}


def test_report_counts_labels_and_skips(mocap):
    root, _, out, report = mocap
    assert sum(report["clips"].values()) == 12 and all(n > 0 for n in report["clips"].values())
    skipped = {s["clip"]: s["reason"] for s in report["skipped"]}
    assert set(skipped) == {"jump/thumbless", "walk/cut"}
    assert "differ" in skipped["jump/thumbless"] and "truncated" in skipped["walk/cut"]
    meta = json.loads((out / "meta.json").read_text())
    assert meta["labels"] == {"dataset": ["mocap"], "content": ["hop", "jump", "walk"],
                              "style": ["happy", "unlabelled"]}  # fmt: skip
    assert report["options"]["source_type"] == "bvh" and report["sources"] == [str(root.resolve())]
    assert JointMap.load(out / "joint_map.json").joints["l_ankle"] == ["LeftFoot"]
    assert "--labels labels.csv" in (out / "README.md").read_text()


def test_labels_captions_and_flags(mocap):
    found = {}
    for data in all_clips(mocap[2]).values():
        for i, cid in enumerate(data.arrays["ids"]):
            found[str(cid)] = (data.label("content", i), data.label("style", i), data.captions(i),
                               data.captions_generated(i), data.records()[i].meta["captions_generated"])  # fmt: skip
    assert len(found) == 12
    assert found["walk/w0"][:4] == ("walk", "happy", ["a person strolls forward.", "someone walks ahead happily."],
                                    False)  # fmt: skip
    assert found["walk/w2"][2:4] == (["a person walks."], False)
    assert found["jump/j1"][:2] == ("hop", "unlabelled") and found["jump/j1"][3] is True
    assert found["jump/j3"][:2] == ("jump", "unlabelled") and found["jump/j3"][3] is True
    assert all(f[3] == f[4] for f in found.values())
    assert found["jump/j3"][2][0].endswith(" jumps.")  # generated from the folder name


def test_inferred_map_follows_cmu_conventions(mocap):
    jm = JointMap.load(mocap[2] / "joint_map.json")
    assert jm.units_to_metres == 0.01  # legs of 82 units -> centimetres
    j = jm.joints
    assert j["pelvis"] == ["Hips"] and j["l_hip"] == ["LeftUpLeg"] and j["l_knee"] == ["LeftLeg"]
    assert j["l_ankle"] == ["LeftFoot"] and j["r_foot"] == ["RightToeBase"] and j["head"] == ["Head"]
    # Zero-offset joints sit on their parent: LowerBack and Neck are skipped, the collar is between its ends.
    assert (j["spine1"], j["spine2"], j["spine3"]) == (["Spine"], ["Spine", "Spine1"], ["Spine1"])
    assert j["neck"] == ["Neck1"] and j["l_collar"] == ["LeftShoulder", "LeftArm"]
    assert (j["l_shoulder"], j["l_elbow"], j["l_wrist"]) == (["LeftArm"], ["LeftForeArm"], ["LeftHand"])


# l_ankle is LeftFoot, l_foot LeftToeBase, ...: bones between SMPL-22 joints and the source joints they map to
SMPL_BONES = [(4, 7), (7, 10), (5, 8), (18, 20), (19, 21), (16, 18)]
SOURCE_BONES = [("LeftLeg", "LeftFoot"), ("LeftFoot", "LeftToeBase"), ("RightLeg", "RightFoot"),
                ("LeftForeArm", "LeftHand"), ("RightForeArm", "RightHand"), ("LeftArm", "LeftForeArm")]  # fmt: skip


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _rigid_residual(a: np.ndarray, b: np.ndarray, centre: bool = True) -> float:
    """Largest distance between point sets after the best rotation (+ translation) of a onto b (Kabsch)."""
    a, b = a.reshape(-1, 3), b.reshape(-1, 3)
    ca, cb = (a - a.mean(0), b - b.mean(0)) if centre else (a, b)
    u, _, vt = np.linalg.svd(ca.T @ cb)
    d = np.sign(np.linalg.det(u @ vt))
    rot = u @ np.diag([1, 1, d]) @ vt
    return float(np.abs(ca @ rot - cb).max())


def test_rotations_and_joints_match_the_files(mocap):
    root, _, out, _ = mocap
    spec = human_spec()
    source_bones = [tuple(CMU_NAMES.index(n) for n in pair) for pair in SOURCE_BONES]
    for data in all_clips(out).values():
        for i, clip in enumerate(data.clips()):
            cid = str(data.arrays["ids"][i])
            seed = int(cid[-1]) + (10 if cid.startswith("jump") else 0)
            world = reference_positions(spec, walk_values(spec, 90, seed))[::3] * 0.01  # 60 -> 20 fps, metres
            native = clip.rig_positions()
            assert native.shape == world.shape and _rigid_residual(native, world) < 1e-4
            # SMPL-22 joints are HumanML3D-proportioned copies (facing read after that rescaling, so turned by
            # a small constant yaw): bone directions match the mapped source joints' up to one rotation.
            d22 = np.concatenate([_unit(clip.joints[:, b] - clip.joints[:, a]) for a, b in SMPL_BONES])
            dn = np.concatenate([_unit(native[:, b] - native[:, a]) for a, b in source_bones])
            assert _rigid_residual(d22, dn, centre=False) < 1e-4, cid  # a wrong joint gives ~0.5
    assert float(data.arrays["fps"]) == TARGET_FPS


def test_command_line_without_labels(mocap, tmp_path, capsys):
    """Actions from the sub-folders, generated captions for all, clips cropped to their most active 20 frames."""
    root = mocap[0]
    argv = ["bvh", "--src", str(root), "--out", str(tmp_path / "out"), "--max-frames", "20", "--workers", "1"]
    assert main(argv) == 0
    printed = capsys.readouterr().out
    assert "prepared 12 clips" in printed and "walk/cut: " in printed
    meta = json.loads((tmp_path / "out" / "meta.json").read_text())
    assert meta["labels"]["content"] == ["jump", "walk"] and meta["labels"]["style"] == ["unlabelled"]
    for split in ("train", "val", "test"):
        a = load_split(tmp_path / "out", split).arrays
        assert a["captions_generated"].shape == () and bool(a["captions_generated"]) and a["lengths"].max() == 20
    assert "--src mocap --joint-map auto --max-frames 20" in (tmp_path / "out" / "README.md").read_text()


def test_zip_gives_the_same_arrays(mocap, tmp_path):
    root, labels, out, _ = mocap
    archive = tmp_path / "mocap.zip"
    with zipfile.ZipFile(archive, "w") as z:
        for p in sorted(root.rglob("*.bvh")):
            z.write(p, f"mocap/{p.relative_to(root).as_posix()}")  # one top folder, as zips often have
    prepare_bvh([archive], tmp_path / "z", labels, workers=1, progress=False)
    # then again in the same process with worker processes: forked workers must not read through a zip handle this
    # process kept open (a shared file offset corrupts inflating: "invalid distance too far back")
    assert writer._SOURCES == {}, "a zip stayed open after preparing"
    prepare_bvh([archive], tmp_path / "z2", labels, workers=2, progress=False)
    for split, a in all_clips(out).items():
        for folder in ("z", "z2"):
            b = load_split(tmp_path / folder, split)
            assert a.arrays.keys() == b.arrays.keys()
            for k in a.arrays:
                np.testing.assert_array_equal(a.arrays[k], b.arrays[k], err_msg=f"{folder} {split}/{k}")


def test_ensure_prepared_reuses_and_refreshes(mocap, tmp_path):
    root, labels, out, _ = mocap
    before = (out / "train.npz").stat().st_mtime_ns
    assert ensure_prepared_bvh(root, out, labels, workers=1) == out  # same sources and options: reused
    assert (out / "train.npz").stat().st_mtime_ns == before
    copy = tmp_path / "copy"
    shutil.copytree(out, copy)
    ensure_prepared_bvh(root, copy, labels, max_frames=20, workers=1)  # other options: prepared again
    assert load_split(copy, "train").arrays["lengths"].max() <= 20
    (copy / "report.json").write_text(json.dumps({"sources": [], "options": {}}))
    with pytest.raises(PrepareError, match="holds another prepared dataset"):
        ensure_prepared_bvh(root, copy, labels)


# ---- errors: one clear message, before any work --------------------------------------------------------------
def test_labels_rows_naming_missing_files_or_unknown_columns(mocap, tmp_path):
    root = mocap[0]
    bad = tmp_path / "bad.csv"
    bad.write_text("file,action\nwalk/w0.bvh,walk\nnope.bvh,run\nw1.bvh,a\nwalk/w1.bvh,b\n")
    with pytest.raises(PrepareError, match=r"2 bad row\(s\)") as err:
        prepare_bvh([root], tmp_path / "out", bad, workers=1, progress=False)
    assert "row 3: no BVH file 'nope.bvh'" in str(err.value) and "row 5: 'walk/w1.bvh' is labelled twice" in str(
        err.value
    )
    bad.write_text("file,mood\nwalk/w0.bvh,x\n")
    with pytest.raises(PrepareError, match="unknown column.*mood"):
        prepare_bvh([root], tmp_path / "out", bad, progress=False)
    assert not (tmp_path / "out").exists()


def test_unmatched_joint_names_and_empty_folder(tmp_path, capsys):
    spec = human_spec()
    spec.names = [n.replace("LeftUpLeg", "Thing").replace("Head", "Top") for n in CMU_NAMES]
    write_bvh(tmp_path / "odd" / "a.bvh", 0, spec)
    code = main(["bvh", "--src", str(tmp_path / "odd"), "--out", str(tmp_path / "out")])
    message = capsys.readouterr().err
    assert code == 2 and "l_hip, head" in message and "--joint-map path.json" in message
    (tmp_path / "empty" / "sub").mkdir(parents=True)
    with pytest.raises(PrepareError, match="no .bvh files"):
        prepare_bvh([tmp_path / "empty"], tmp_path / "out", progress=False)
    assert not (tmp_path / "out").exists()


# ---- the joint-map guess ---------------------------------------------------------------------------------------
MIXAMO = ["Hips", "Spine", "Spine1", "Spine2", "Neck", "Head", "LeftShoulder", "LeftArm", "LeftForeArm", "LeftHand",
          "RightShoulder", "RightArm", "RightForeArm", "RightHand", "LeftUpLeg", "LeftLeg", "LeftFoot",
          "LeftToeBase", "RightUpLeg", "RightLeg", "RightFoot", "RightToeBase"]  # fmt: skip
MIXAMO_PARENTS = [-1, 0, 1, 2, 3, 4, 3, 6, 7, 8, 3, 10, 11, 12, 0, 14, 15, 16, 0, 18, 19, 20]
STYLE100 = ["Hips", "Chest", "Chest2", "Chest3", "Chest4", "Neck", "Head", "RightCollar", "RightShoulder",
            "RightElbow", "RightWrist", "LeftCollar", "LeftShoulder", "LeftElbow", "LeftWrist", "RightHip",
            "RightKnee", "RightAnkle", "RightToe", "LeftHip", "LeftKnee", "LeftAnkle", "LeftToe"]  # fmt: skip
STYLE100_PARENTS = [-1, 0, 1, 2, 3, 4, 5, 4, 7, 8, 9, 4, 11, 12, 13, 0, 15, 16, 17, 0, 19, 20, 21]


def test_mixamo_and_100style_conventions():
    mix = JointMap.infer([f"mixamorig:{n}" for n in MIXAMO], MIXAMO_PARENTS, 0.01).joints
    assert mix["spine2"] == ["mixamorig:Spine1"] and mix["l_collar"] == ["mixamorig:LeftShoulder"]
    assert mix["l_shoulder"] == ["mixamorig:LeftArm"] and mix["r_foot"] == ["mixamorig:RightToeBase"]
    sty = JointMap.infer(STYLE100, STYLE100_PARENTS, 1.0).joints
    assert (sty["spine1"], sty["spine2"], sty["spine3"]) == (["Chest"], ["Chest2", "Chest3"], ["Chest4"])
    assert sty["l_collar"] == ["LeftCollar"] and sty["l_shoulder"] == ["LeftShoulder"]  # Shoulder = upper arm
    assert sty["l_ankle"] == ["LeftAnkle"] and sty["l_foot"] == ["LeftToe"] and sty["l_hip"] == ["LeftHip"]


@pytest.mark.parametrize("leg,units", [(0.82, 1.0), (82, 0.01), (32, 0.0254), (820, 0.001), (14.5, 0.0254 / 0.45)])
def test_units_from_leg_length(leg, units):
    offsets = np.array([[0, 1, 0]] + [[0, -leg / 2, 0] if n in ("LeftLeg", "LeftFoot", "RightLeg", "RightFoot")
                                      else [0, 1, 0] for n in MIXAMO[1:]], dtype=float)  # fmt: skip
    assert JointMap.infer(MIXAMO, MIXAMO_PARENTS, offsets=offsets).units_to_metres == pytest.approx(units)


def test_100style_file_names():
    assert path_labels("Aeroplane/Aeroplane_BR.bvh", True) == ("run-back", "aeroplane")
    assert path_labels("ArmsAboveHead/ArmsAboveHead_FW.bvh", True) == ("walk", "arms-above-head")
    assert path_labels("Angry_TR2.bvh", False) == ("transition", "angry")
    assert path_labels("data/dataset-1_bow_old_001.bvh", False) == ("unlabelled", "unlabelled")
    assert path_labels("Kicks/k_01.bvh", True) == ("kicks", "unlabelled")


def test_infer_on_the_real_bandai_skeleton_matches_the_shipped_map(shared):
    from motiondiff.data.formats.bvh import parse_bvh

    with zipfile.ZipFile(shared("data", "bandai-namco", "bandai-ds1.zip")) as z:
        name = next(n for n in z.namelist() if n.endswith(".bvh"))
        motion = parse_bvh(z.read(name).decode())
    inferred = JointMap.infer(motion.joint_names, motion.parents, offsets=motion.offsets)
    shipped = JointMap.load("bandai_to_smpl22")
    assert inferred.joints == shipped.joints and inferred.units_to_metres == shipped.units_to_metres
