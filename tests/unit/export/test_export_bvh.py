"""BVH export (motiondiff.export.bvh_export) and export_motion: export -> read_bvh -> FK gives back the exported
joints (acceptance: <= 1e-3 m) on synthetic motions and on every real clip of the embedded val split, through IK
(positions) and as written rotations (rotation representations), plus units, fit reports and bad input; End Sites
of real length on every leaf, and the files read by bvhio (an independent reader) with no zero-length bone."""

from __future__ import annotations

import os

import numpy as np
import pytest
from fixtures.bvh_reader import bone_lengths, bvhio_positions
from scipy.spatial.transform import Rotation

from motiondiff.data.datamodules import embedded_data_root
from motiondiff.data.formats.bvh import BVHMotion, read_bvh
from motiondiff.data.formats.prepared import load_split
from motiondiff.data.representations import ROTATION_REPRESENTATIONS, get_representation
from motiondiff.export import FORMATS, ExportReport, export_bvh, export_bvh_from_features, export_motion
from motiondiff.geometry.kinematics import forward_kinematics
from motiondiff.geometry.rotations import qangle
from motiondiff.geometry.skeleton import SMPL22, Skeleton

TOL = 1e-3  # metres: the acceptance criterion of the BVH round trip


@pytest.fixture(scope="module")
def val():
    split = load_split(embedded_data_root(), "val")
    return split.rig(), split.clips()


def read_positions(path, skeleton: Skeleton, scale: float = 1.0) -> np.ndarray:
    """World positions (N, J, 3) of a written BVH, metres, in the skeleton's joint order (files are depth-first)."""
    motion = read_bvh(path)
    assert sorted(motion.joint_names) == sorted(skeleton.joint_names)
    return motion.scaled(1.0 / scale).positions()[:, joint_order(motion, skeleton)]


def joint_order(motion: BVHMotion, skeleton: Skeleton) -> list[int]:
    return [motion.joint_names.index(n) for n in skeleton.joint_names]


def random_motion(frames=30, seed=0):
    rotations = Rotation.random(frames * 22, random_state=seed).as_quat()[:, [3, 0, 1, 2]].reshape(frames, 22, 4)
    translations = np.repeat(SMPL22.offsets[None], frames, axis=0)
    translations[:, 0] = np.random.default_rng(seed).normal(size=(frames, 3)) + [0, 1, 0]
    return rotations, translations[:, 0], forward_kinematics(rotations, translations, SMPL22.parents)[0]


# ---- synthetic ----------------------------------------------------------------------------------------------------
def test_synthetic_positions_round_trip_through_the_file(tmp_path):
    _, _, joints = random_motion()
    report = export_bvh(tmp_path / "random.bvh", joints, SMPL22, fps=20)
    assert isinstance(report, ExportReport) and report.method == "ik" and report.frames == 30
    assert os.fspath(report) == str(tmp_path / "random.bvh")
    err = np.linalg.norm(read_positions(report.path, SMPL22) - joints, axis=-1).max()
    assert err <= 1e-5 and report.max_error <= 1e-9
    motion = read_bvh(report.path)
    assert motion.fps == 20.0 and motion.num_frames == 30
    names = motion.joint_names
    parents = {n: (names[p] if p >= 0 else None) for n, p in zip(names, motion.parents.tolist(), strict=True)}
    assert parents == {n: (SMPL22.joint_names[p] if p >= 0 else None) for n, p in zip(SMPL22.joint_names, SMPL22.parents, strict=True)}  # fmt: skip


def test_rotations_are_written_as_given(tmp_path):
    rotations, root, joints = random_motion(seed=1)
    report = export_bvh(tmp_path / "rot.bvh", joints, SMPL22, 30, rotations=rotations, root=root)
    assert report.method == "rotations" and report.max_error <= 1e-9
    motion = read_bvh(report.path)
    # every joint's rotation comes back, also the twists IK could not have known
    assert qangle(motion.rotations[:, joint_order(motion, SMPL22)], rotations).max() < 1e-6
    assert np.linalg.norm(read_positions(report.path, SMPL22) - joints, axis=-1).max() <= 1e-5


def test_scale_writes_other_units(tmp_path):
    _, _, joints = random_motion(seed=2)
    report = export_bvh(tmp_path / "cm.bvh", joints, SMPL22, 20, scale=100.0)
    motion = read_bvh(report.path)
    hip = motion.joint_names.index("l_hip")
    assert 5 < np.linalg.norm(motion.offsets[hip]) < 20  # centimetres (the bone is ~10 cm)
    assert np.linalg.norm(read_positions(report.path, SMPL22, scale=100.0) - joints, axis=-1).max() <= 1e-5


# ---- real data ----------------------------------------------------------------------------------------------------
def test_real_clips_round_trip_from_positions(val, tmp_path):
    """The acceptance criterion: export from positions -> read_bvh -> FK equals the exported joints to <= 1e-3 m."""
    _, clips = val
    worst = worst_reported = 0.0
    for i, clip in enumerate(clips):
        report = export_bvh(tmp_path / f"clip{i}.bvh", clip.joints, SMPL22, fps=20)
        err = float(np.linalg.norm(read_positions(report.path, SMPL22) - clip.joints, axis=-1).max())
        assert abs(err - report.max_error) < 1e-5  # the report tells the truth about the file
        worst, worst_reported = max(worst, err), max(worst_reported, report.max_error)
    print(
        f"\nBVH round trip, {len(clips)} real SMPL-22 clips from positions: max {worst:.2e} m (reported {worst_reported:.2e})"
    )
    assert worst <= TOL


def test_nominal_offsets_show_up_in_the_fit_error(val, tmp_path):
    """The report is not a formality: forcing the skeleton's nominal offsets (other bone lengths and pelvis/chest
    arrangement than the data) makes the fit visibly worse, and the report says so."""
    _, clips = val
    report = export_bvh(tmp_path / "nominal.bvh", clips[0].joints, SMPL22, 20, offsets=SMPL22.offsets)
    err = np.linalg.norm(read_positions(report.path, SMPL22) - clips[0].joints, axis=-1).max()
    assert report.max_error > 0.01 and abs(err - report.max_error) < 1e-5


@pytest.mark.parametrize("name", [*ROTATION_REPRESENTATIONS, "jp", "hml263"])
def test_real_clip_features_round_trip(val, tmp_path, name):
    """Rotation representations write their own rotations (no IK); jp (rig positions) and hml263 (SMPL-22) go
    through IK. The file gives back the representation's decoding, and for rotations the clip's own rotations."""
    rig, clips = val
    clip = clips[17]
    rep = get_representation(name, SMPL22, rig)
    feats = rep.encode(clip)
    offsets = None if name == "hml263" else clip.offsets
    report = export_bvh_from_features(tmp_path / f"{name}.bvh", rep, feats, fps=20, offsets=offsets)
    expected = clip.joints[: len(feats)] if name == "hml263" else clip.rig_positions()
    err = np.linalg.norm(read_positions(report.path, rep.skeleton) - expected, axis=-1).max()
    print(f"\n{name}: method {report.method}, BVH round trip max {err:.2e} m")
    assert err <= TOL
    assert report.method == ("rotations" if name in ROTATION_REPRESENTATIONS else "ik")
    if name in ROTATION_REPRESENTATIONS:
        motion = read_bvh(report.path)
        assert qangle(motion.rotations[:, joint_order(motion, rig)], clip.rotations).max() < 1e-5


# ---- export_motion --------------------------------------------------------------------------------------------------
def test_export_motion_writes_every_format(val, tmp_path):
    _, clips = val
    joints = clips[0].joints[:4]
    formats = ["npy", "bvh", "html", "gif", "npy"]
    paths = export_motion(tmp_path / "walk.v1", joints, SMPL22, 20, formats, title="t", video_size=120)
    assert list(paths) == ["npy", "bvh", "html", "gif"]
    assert {p.name for p in tmp_path.iterdir()} == {"walk.v1.npy", "walk.v1.bvh", "walk.v1.html", "walk.v1.gif"}
    np.testing.assert_array_equal(np.load(paths["npy"]), joints)
    assert np.linalg.norm(read_positions(paths["bvh"], SMPL22) - joints, axis=-1).max() <= TOL
    assert paths["gif"].read_bytes()[:3] == b"GIF"


def test_export_motion_refuses_unknown_formats_before_writing(tmp_path):
    _, _, joints = random_motion(frames=3)
    with pytest.raises(ValueError, match="unknown export format.*'fbx'.*npy, mp4, gif, bvh, html"):
        export_motion(tmp_path / "x", joints, SMPL22, 20, ["npy", "fbx"])
    assert list(tmp_path.iterdir()) == [] and FORMATS == ("npy", "mp4", "gif", "bvh", "html")


# ---- bad input ----------------------------------------------------------------------------------------------------
def test_bad_input_is_refused_and_leaves_nothing(tmp_path, val):
    rotations, root, joints = random_motion(frames=5)
    target = tmp_path / "bad.bvh"
    with pytest.raises(ValueError, match=r"\(frames >= 1, 22, 3\).*decode features first"):
        export_bvh(target, joints[:, :21], SMPL22, 20)
    nan = joints.copy()
    nan[3, 2, 1] = np.inf
    with pytest.raises(ValueError, match=r"NaN or Inf in 1 frame\(s\) \(first: 3\)"):
        export_bvh(target, nan, SMPL22, 20)
    with pytest.raises(ValueError, match="both rotations and root"):
        export_bvh(target, joints, SMPL22, 20, rotations=rotations)
    with pytest.raises(ValueError, match=r"rotations must be \(5, 22, 4\)"):
        export_bvh(target, joints, SMPL22, 20, rotations=rotations[:, :, :3], root=root)
    with pytest.raises(ValueError, match="fps must be a positive"):
        export_bvh(target, joints, SMPL22, 0)
    with pytest.raises(ValueError, match="offsets must be finite with shape"):
        export_bvh(target, joints, SMPL22, 20, offsets=np.zeros((3, 3)))
    rig, _ = val
    rep = get_representation("rp6jr", SMPL22, rig)
    with pytest.raises(ValueError, match=f"features must have shape \\(frames, {rep.dim}\\)"):
        export_bvh_from_features(target, rep, np.zeros((5, rep.dim + 1)), 20)
    with pytest.raises(FileNotFoundError, match="does not exist"):
        export_bvh(tmp_path / "missing" / "deeper" / "x.bvh", joints, SMPL22, 20)
    assert list(tmp_path.iterdir()) == []


# ---- End Sites, and the files read by an independent reader ---------------------------------------------------------
def test_an_independent_reader_gives_back_every_real_clip_in_centimetres(val, tmp_path):
    """The acceptance criterion with bvhio instead of the project's reader: the 22 joints' world positions of every
    frame, after units, equal the exported joints to <= 1e-3 m; no bone in any file has zero length."""
    _, clips = val
    worst, shortest = 0.0, np.inf
    for i, clip in enumerate(clips):
        path = export_bvh(tmp_path / f"clip{i}.bvh", clip.joints, SMPL22, fps=20, scale=100.0).path
        positions = bvhio_positions(path, SMPL22.joint_names) / 100.0
        assert positions.shape == clip.joints.shape
        worst = max(worst, float(np.linalg.norm(positions - clip.joints, axis=-1).max()))
        lengths = bone_lengths(path)
        assert len([k for k in lengths if k.startswith("End Site")]) == 5
        shortest = min(shortest, min(lengths.values()) / 100.0)
    print(f"\nbvhio, {len(clips)} real clips exported in cm: max position error {worst:.2e} m, shortest bone "
          f"{shortest:.4f} m")  # fmt: skip
    assert worst <= TOL and shortest > 0.01


def test_rotation_representation_files_read_by_bvhio(val, tmp_path):
    """A rotation representation's file (the Bandai rig, rotations written as given) also reads back in bvhio, and
    its leaves (Head, Hand_L/R, Toes_L/R) have End Sites of real length too."""
    rig, clips = val
    rep = get_representation("rp6jr", SMPL22, rig)
    report = export_bvh_from_features(tmp_path / "rig.bvh", rep, rep.encode(clips[3]), fps=20, offsets=clips[3].offsets)
    positions = bvhio_positions(report.path, rig.joint_names)
    assert np.linalg.norm(positions - clips[3].rig_positions(), axis=-1).max() <= TOL
    lengths = bone_lengths(report.path)
    assert {k for k in lengths if k.startswith("End Site")} == {f"End Site {n}" for n in
                                                                 ("Head", "Hand_L", "Hand_R", "Toes_L", "Toes_R")}  # fmt: skip
    assert min(lengths.values()) > 0.01


def test_end_sites_have_anatomical_lengths_along_the_leaf_bone(val, tmp_path):
    _, clips = val
    report = export_bvh(tmp_path / "walk.bvh", clips[0].joints, SMPL22, fps=20)
    motion = read_bvh(report.path)
    names = motion.joint_names
    leg = sum(np.linalg.norm(motion.offsets[names.index(n)]) for n in ("r_knee", "r_ankle"))
    stature = leg / 0.491
    assert 1.4 < stature < 2.0
    expected = {"head": 0.065, "l_foot": 0.041, "r_foot": 0.041, "l_wrist": 0.108, "r_wrist": 0.108}
    assert {names[j] for j in motion.end_sites} == set(expected)
    for j, site in motion.end_sites.items():
        bone = motion.offsets[j]
        assert np.isclose(np.linalg.norm(site), expected[names[j]] * stature)
        assert np.allclose(site / np.linalg.norm(site), bone / np.linalg.norm(bone))  # the leaf's bone, continued
    # on HumanML3D's target skeleton: the hand 0.18 m, the toes 0.07 m, the top of the head 0.11 m
    sites = SMPL22.end_sites()
    assert np.allclose([np.linalg.norm(sites[j]) for j in (20, 10, 15)], [0.1795, 0.0681, 0.1080], atol=5e-4)


def test_every_skeleton_gets_end_sites_of_real_length():
    from motiondiff.data.formats.bvh import continued_end_sites
    from motiondiff.geometry.skeleton import KIT21, SMPL24

    for skeleton in (SMPL22, KIT21, SMPL24):
        sites = skeleton.end_sites()
        assert set(sites) == {j for j, kids in enumerate(skeleton.children) if not kids}
        assert min(np.linalg.norm(v) for v in sites.values()) > 0.01
    bare = Skeleton.infer("bare", ["root", "a", "b"], [-1, 0, 1], np.array([[0, 0, 0], [0, 1, 0], [0, 0, 0]]))
    assert np.allclose(bare.end_sites()[2], [0, 1, 0])  # a zero leaf bone: its parent's bone, continued
    assert np.allclose(continued_end_sites([-1, 0, 0], [[0, 0, 0], [2, 0, 0], [0, 0, 3]])[2], [0, 0, 3])
