"""Representations on real data: round trips on every val clip of the embedded dataset, decoding against the BVH
reader's own FK and the official HumanML3D sample, joint_dims masks, foot contacts and error messages."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from motiondiff.data.datamodules import embedded_data_root
from motiondiff.data.formats.prepared import load_split
from motiondiff.data.representations import (
    REPRESENTATIONS,
    ROTATION_REPRESENTATIONS,
    Representation,
    get_representation,
)
from motiondiff.data.representations import hml_features as F
from motiondiff.data.representations.clip import ClipMotion
from motiondiff.geometry.rotations import qrot
from motiondiff.geometry.skeleton import KIT21, SMPL22

RIG_REPS = ("jp", *ROTATION_REPRESENTATIONS)
TOL = 1e-4  # metres


@pytest.fixture(scope="module")
def val():
    split = load_split(embedded_data_root(), "val")
    return split.rig(), split.clips()


def rep_for(name: str, rig) -> Representation:
    return get_representation(name, KIT21 if name == "kit251" else SMPL22, rig)


def decode32(rep: Representation, feats: np.ndarray, offsets=None) -> np.ndarray:
    off = None if offsets is None else torch.as_tensor(offsets, dtype=torch.float32)
    return rep.decode(torch.from_numpy(feats), off).numpy()


def kit_joints() -> np.ndarray:
    """Canonical KIT-21 joints (no KIT data ships): rest pose from the raw offsets, a small smooth sway (larger
    sways flip HumanML3D's facing, whose hip and shoulder terms nearly cancel), walking forward."""
    rng = np.random.default_rng(0)
    rest = np.zeros((21, 3))
    for j, p in enumerate(KIT21.parents[1:], start=1):
        rest[j] = rest[p] + 0.2 * KIT21.raw_offsets[j]
    rest[:, 1] -= rest[:, 1].min()
    t = np.linspace(0, 2 * np.pi, 60)[:, None, None]
    joints = rest[None] + 0.02 * np.sin(t + rng.uniform(0, 6, (1, 21, 3))) + np.array([0, 0, 1.0]) * t / 5
    return F.canonicalize_joints(joints, KIT21).astype(np.float32)


# ---- 1. round trips -------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", [n for n in REPRESENTATIONS if n != "kit251"])
def test_round_trip_on_every_real_val_clip(val, name):
    rig, clips = val
    rep = rep_for(name, rig)
    worst = 0.0
    for clip in clips:
        feats = rep.encode(clip)
        assert feats.dtype == np.float32 and feats.shape == (clip.num_frames - rep.frames_dropped, rep.dim)
        out = decode32(rep, feats, clip.offsets)
        # hml row i is frame i (velocities point to frame i+1), so N-1 rows decode to frames 0..N-2
        ref = clip.joints[: len(feats)] if name == "hml263" else clip.rig_positions()
        assert out.dtype == np.float32 and out.shape == ref.shape
        worst = max(worst, float(np.abs(out - ref).max()))
    print(f"\n{name:7s} dim {rep.dim:3d}: max |decode(encode) - input| over {len(clips)} val clips = {worst:.2e} m")
    assert worst <= TOL


def test_jp_without_rig_uses_feature_joints(val):
    _, clips = val
    rep = get_representation("jp", SMPL22)
    assert rep.skeleton is SMPL22 and rep.dim == 66 and not rep.needs_rotations
    clip = ClipMotion(joints=clips[0].joints)  # a positions-only dataset
    assert np.abs(decode32(rep, rep.encode(clip)) - clip.joints).max() == 0


def test_kit251_round_trip():
    joints = kit_joints()
    rep = get_representation("kit251", KIT21)
    feats = rep.encode(ClipMotion(joints=joints))
    err = np.abs(decode32(rep, feats) - joints[:-1]).max()
    print(f"\nkit251  dim {rep.dim}: max |decode(encode) - input| (synthetic KIT-21 clip) = {err:.2e} m")
    assert feats.shape == (59, 251) and err <= TOL


def test_hml_torch_decode_matches_numpy_and_official_sample(shared):
    root = shared("reference", "humanml3d")
    vecs = np.load(root / "new_joint_vecs" / "012314.npy")
    joints = np.load(root / "new_joints" / "012314.npy")
    rep = get_representation("hml263", SMPL22)
    out = decode32(rep, vecs.astype(np.float32))
    err = np.abs(out - joints).max()
    print(f"\nhml263 official 012314: max |decode(new_joint_vecs) - new_joints| = {err:.2e} m")
    assert err <= TOL
    assert np.abs(rep.decode_numpy(vecs) - F.joints_from_features(vecs)).max() <= 1e-5


def test_decode_batched_with_per_clip_offsets(val):
    rig, clips = val
    rep = rep_for("rp6jr", rig)
    a, b = clips[0], clips[1]
    n = min(a.num_frames, b.num_frames)
    feats = torch.from_numpy(np.stack([rep.encode(a)[:n], rep.encode(b)[:n]]))
    offsets = torch.from_numpy(np.stack([a.offsets, b.offsets])).float()
    out = rep.decode(feats, offsets)
    assert out.shape == (2, n, rig.num_joints, 3)
    for i, c in enumerate((a, b)):
        assert np.abs(out[i].numpy() - c.rig_positions()[:n]).max() <= TOL
    # offsets=None means the rig's (mean) offsets; other offsets give other bones
    assert np.abs(rep.decode_numpy(feats[0].numpy()) - a.rig_positions()[:n]).max() <= 1e-3
    longer = rep.decode_numpy(feats[0].numpy(), a.offsets * 1.1)
    bones = np.linalg.norm(longer[:, 1:] - longer[:, list(rig.parents[1:])], axis=-1)
    np.testing.assert_allclose(bones, np.broadcast_to(1.1 * np.linalg.norm(a.offsets[1:], axis=-1), bones.shape))
    assert rep.decode_numpy(feats[0].numpy(), a.offsets).dtype == np.float64


# ---- 2. decoding equals the BVH reader's own FK ---------------------------------------------------------------
# a clip that travels (root path) and one with large limb rotations
@pytest.fixture(scope="module", params=["dataset-1_walk-back_normal_001", "dataset-1_kick_normal_001"])
def bvh_clip(shared, request):
    from motiondiff.data.formats.archive import Source
    from motiondiff.data.formats.bvh import parse_bvh
    from motiondiff.data.formats.joint_map import JointMap
    from motiondiff.data.preparing.processing import TARGET_FPS, process_motion
    from motiondiff.data.representations.hml_features import ground_and_face
    from motiondiff.data.sources import bandai

    source = Source(shared("data", "bandai-namco", "bandai-ds1.zip"))
    clips, _ = bandai.list_clips(source)
    clip = next(c for c in clips if c.name == request.param)
    motion = parse_bvh(source.read_text(clip.bvh_name), clip.bvh_name)
    joint_map = JointMap.load("bandai_to_smpl22")
    processed = process_motion(motion, joint_map)
    rig = processed.native.skeleton("native")
    # reference: the BVH reader's FK of the same resampled, scaled motion (placeholder root included), the
    # placeholder dropped, then the canonical placement (floor, origin, facing +Z) computed from those positions
    m = motion.resample(TARGET_FPS).scaled(joint_map.units_to_metres)
    world = m.positions()
    assert m.joint_names[1:] == processed.native.joint_names  # joint_Root was folded into Hips
    world = world[:, 1:]
    turn, shift = ground_and_face(world, rig)
    ref = qrot(np.broadcast_to(turn, world.shape[:-1] + (4,)), world + shift)
    cm = ClipMotion(
        joints=processed.joints,
        rotations=processed.native_rotations,
        root=processed.native_root,
        offsets=processed.native.offsets,
        rig=rig,
    )
    return cm, ref


@pytest.mark.shared
@pytest.mark.parametrize("name", RIG_REPS)
def test_rotation_decode_equals_bvh_fk(bvh_clip, name):
    clip, ref = bvh_clip
    rep = get_representation(name, SMPL22, clip.rig)
    out = decode32(rep, rep.encode(clip), clip.offsets)
    err = np.abs(out - ref).max()
    print(f"\n{name:7s}: max |decode - BVH FK| = {err:.2e} m over {len(ref)} frames")
    assert np.ptp(ref[:, 0, [0, 2]], axis=0).max() > 0.5  # the root path is really tested
    assert err <= TOL


# ---- 4. joint_dims --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", REPRESENTATIONS)
def test_joint_dims_partition_the_features(val, name):
    rep = rep_for(name, val[0])
    dims = rep.joint_dims()
    assert len(dims) == rep.skeleton.num_joints
    flat = [d for js in dims for d in js]
    assert sorted(flat) == list(range(rep.dim))  # disjoint and covering
    assert {0, 1, 2} <= set(dims[0])  # the root owns the trajectory


def descendants(parents, k: int) -> set[int]:
    out = {k}
    for j, p in enumerate(parents):
        if p in out:
            out.add(j)
    return out


@pytest.mark.parametrize("name", RIG_REPS)
def test_joint_dims_only_move_descendants(val, name):
    rig, clips = val
    rep = rep_for(name, rig)
    clip = clips[3]
    feats = torch.from_numpy(rep.encode(clip)).double()
    base = rep.decode(feats, clip.offsets)
    gen = torch.Generator().manual_seed(0)
    for joint in ("Spine", "UpperArm_L", "LowerLeg_R", "Foot_L"):
        k = rig.index(joint)
        moved = feats.clone()
        moved[:, rep.joint_dims()[k]] += 0.3 * torch.randn(len(feats), len(rep.joint_dims()[k]), generator=gen)
        diff = (rep.decode(moved, clip.offsets) - base).abs().amax(dim=(0, 2))
        below = descendants(rig.parents, k)
        # jp: only the joint itself; rotations: the joint's own position stays, its subtree moves
        changed = {k} if name == "jp" else below - {k}
        others = [j for j in range(rig.num_joints) if j not in changed]
        assert diff[others].max() <= 1e-9, joint
        assert diff[sorted(changed)].min() > 1e-3, joint


# ---- 5. foot contacts -----------------------------------------------------------------------------------------
def test_hml_foot_contacts_are_the_contact_channels(val):
    clip = val[1][0]
    rep = get_representation("hml263", SMPL22)
    feats = rep.encode(clip)
    got = rep.foot_contacts(torch.from_numpy(feats)).numpy()
    assert rep.contact_joints == (7, 10, 8, 11)
    np.testing.assert_array_equal(got, feats[:, F.feature_slices(22)["contacts"]])
    np.testing.assert_array_equal(got, F.foot_contacts(clip.joints, SMPL22))


def test_rotation_foot_contacts_match_features_rule(val):
    rig, clips = val
    rep = rep_for("rp6jr", rig)
    for clip in clips[:8]:
        feats = torch.from_numpy(rep.encode(clip))
        got = rep.foot_contacts(feats, torch.from_numpy(clip.offsets).float()).numpy()
        want = F.foot_contacts(decode32(rep, feats.numpy(), clip.offsets), rig)
        assert got.shape == (clip.num_frames, 4)
        np.testing.assert_array_equal(got[:-1], want)
        np.testing.assert_array_equal(got[-1], got[-2])
    names = [rig.joint_names[j] for j in rep.contact_joints]
    assert names == ["Foot_L", "Toes_L", "Foot_R", "Toes_R"]
    assert 0 < got.mean() < 1  # some frames in contact, some not


# ---- gradients, statistics ------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", [n for n in REPRESENTATIONS if n != "kit251"])
def test_decode_backpropagates_finite_gradients(val, name):
    rig, clips = val
    rep = rep_for(name, rig)
    feats = torch.from_numpy(rep.encode(clips[2])).requires_grad_(True)
    out = rep.decode(feats, torch.from_numpy(clips[2].offsets).float())
    (out**2).sum().backward()
    assert torch.isfinite(feats.grad).all() and feats.grad.abs().sum() > 0


def test_mean_std(val):
    rig, clips = val
    rep = rep_for("rpajr", rig)
    feats = np.concatenate([rep.encode(c) for c in clips])
    feats[:, 5] = 1.5  # a constant dim
    mean, std = rep.mean_std(feats)
    assert mean.shape == std.shape == (rep.dim,) and np.isfinite((feats - mean) / std).all() and std[5] == 1
    hml = get_representation("hml263", SMPL22)
    hfeats = np.concatenate([hml.encode(c) for c in clips[:4]])
    for a, b in zip(hml.mean_std(hfeats), F.mean_std(hfeats), strict=True):
        np.testing.assert_array_equal(a, b)


def test_attributes(val):
    rig, _ = val
    want = {"hml263": 263, "jp": 63, "rp6jr": 129, "rpqjr": 87, "rpajr": 66, "rpejr": 66, "rpmjr": 192}
    for name, dim in want.items():
        rep = rep_for(name, rig)
        assert rep.dim == dim and rep.name == name
        assert rep.frames_dropped == (1 if name == "hml263" else 0)
        assert rep.needs_rotations == (name in ROTATION_REPRESENTATIONS)
        assert rep.skeleton is (SMPL22 if name == "hml263" else rig)
    assert rep_for("kit251", None).dim == 251


def test_quaternions_are_continuous_and_start_with_positive_w(val):
    rig, clips = val
    rep = rep_for("rpqjr", rig)
    for clip in clips:
        q = rep.encode(clip)[:, 3:].reshape(clip.num_frames, rig.num_joints, 4)
        assert (q[0, :, 0] >= 0).all() and ((q[1:] * q[:-1]).sum(-1) >= 0).all()


# ---- 6. errors ------------------------------------------------------------------------------------------------
def test_error_messages():
    with pytest.raises(ValueError, match=r"unknown representation 'rp7jr'; choose from hml263, kit251, jp, rp6jr"):
        get_representation("rp7jr", SMPL22)
    with pytest.raises(ValueError, match=r"'kit21' \(21 joints\): use 'kit251'"):
        get_representation("hml263", KIT21)
    with pytest.raises(ValueError, match=r"'smpl22' \(22 joints\): use 'hml263'"):
        get_representation("kit251", SMPL22)
    for name in ROTATION_REPRESENTATIONS:
        with pytest.raises(ValueError, match=r"stores joint positions only .* work on it: hml263, jp"):
            get_representation(name, SMPL22, None)


def test_bad_inputs(val):
    rig, clips = val
    rep = rep_for("rp6jr", rig)
    with pytest.raises(ValueError, match=r"positions only"):
        rep.encode(ClipMotion(joints=clips[0].joints))
    with pytest.raises(ValueError, match=r"shape \(\.\.\., frames, 129\)"):
        rep.decode(torch.zeros(5, 128))
    with pytest.raises(ValueError, match=r"offsets must have shape"):
        rep.decode(torch.zeros(5, 129), torch.zeros(22, 3))
    with pytest.raises(ValueError, match=r"expected \(frames, 22, 3\)"):
        get_representation("hml263", SMPL22).encode(ClipMotion(joints=np.zeros((5, 21, 3))))
