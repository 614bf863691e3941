"""BVH reader/writer: synthetic files of many layouts (checked against an independent FK), the Bandai clips
and bad input. The synthetic files are written by `bvh_text` below, not by `write_bvh`, so the parser is
tested on text it did not produce."""

from __future__ import annotations

import zipfile
from dataclasses import dataclass

import numpy as np
import pytest

from motiondiff.data.formats import bvh
from motiondiff.data.formats.bvh import BVHError, format_bvh, motion_from_arrays, parse_bvh, read_bvh, write_bvh

ROOT6 = ("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation")
ZXY = ("Zrotation", "Xrotation", "Yrotation")


# ---- building test files -----------------------------------------------------------------------------------
@dataclass
class Spec:
    names: list[str]
    parents: list[int]  # depth-first order, as in a file
    offsets: np.ndarray
    channels: list[tuple[str, ...]]
    end_sites: dict[int, np.ndarray]


def make_spec(names, parents, root_channels, joint_channels, seed=0, end_sites=True) -> Spec:
    rng = np.random.default_rng(seed)
    offsets = rng.uniform(-1, 1, (len(names), 3)) * rng.uniform(3, 20, (len(names), 1))
    offsets[0] = [0.5, 90.0, -3.0]
    channels = [tuple(root_channels) if p < 0 else tuple(joint_channels) for p in parents]
    leaves = sorted(set(range(len(names))) - set(parents)) if end_sites else []
    return Spec(list(names), list(parents), offsets, channels, {j: rng.uniform(-5, 5, 3) for j in leaves})


def smooth_values(spec: Spec, frames: int, seed=1) -> np.ndarray:
    """(F, C) channel values: sums of sines, rotations up to +-150 degrees, root positions in the hundreds."""
    rng = np.random.default_rng(seed)
    t = np.arange(frames)[:, None] / frames
    cols = []
    for chans in spec.channels:
        for ch in chans:
            amp = 150.0 if ch.lower().endswith("rotation") else rng.uniform(1, 300)
            freq, phase = rng.uniform(0.3, 2.0, (1, 2)), rng.uniform(0, 2 * np.pi, (1, 2))
            cols.append(amp * 0.5 * np.sin(2 * np.pi * freq * t + phase).sum(1))
    return np.stack(cols, axis=1)


def bvh_text(spec: Spec, values: np.ndarray, frame_time: float, indent="  ", newline="\n", brace_inline=False):
    lines = ["HIERARCHY"]
    depth: dict[int, int] = {}
    open_joints: list[int] = []

    def close_until(parent):
        while open_joints and open_joints[-1] != parent:
            j = open_joints.pop()
            ind = indent * depth[j]
            if j in spec.end_sites:
                lines.extend([f"{ind}{indent}End Site", f"{ind}{indent}{{",
                              f"{ind}{indent * 2}OFFSET {' '.join(map(repr, spec.end_sites[j].tolist()))}",
                              f"{ind}{indent}}}"])  # fmt: skip
            lines.append(f"{ind}}}")

    for j, p in enumerate(spec.parents):
        close_until(p)
        depth[j] = 0 if p < 0 else depth[p] + 1
        ind = indent * depth[j]
        head = f"{ind}{'ROOT' if p < 0 else 'JOINT'} {spec.names[j]}"
        lines.extend([head + " {"] if brace_inline else [head, f"{ind}{{"])
        lines.append(f"{ind}{indent}OFFSET {' '.join(map(repr, spec.offsets[j].tolist()))}")
        if spec.channels[j]:
            lines.append(f"{ind}{indent}CHANNELS {len(spec.channels[j])} {' '.join(spec.channels[j])}")
        open_joints.append(j)
    close_until(-1)
    lines += ["MOTION", f"Frames:\t{len(values)}", f"Frame Time:\t{frame_time}"]
    lines += [" ".join(repr(v) for v in row) for row in values.tolist()]
    return newline.join(lines) + newline


# ---- an FK that shares nothing with the library's quaternion path ------------------------------------------
def _axis_matrix(axis: str, degrees: float) -> np.ndarray:
    c, s = np.cos(np.radians(degrees)), np.sin(np.radians(degrees))
    return {
        "X": np.array([[1, 0, 0], [0, c, -s], [0, s, c]]),
        "Y": np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]),
        "Z": np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]),
    }[axis]


def reference_positions(spec: Spec, values: np.ndarray) -> np.ndarray:
    """Per-frame loop: local R = product of the axis matrices in channel order; p = p_par + G_par @ t."""
    out = np.zeros((len(values), len(spec.names), 3))
    for f, row in enumerate(values):
        col, glob = 0, []
        for j, (chans, p) in enumerate(zip(spec.channels, spec.parents, strict=True)):
            t, rot = spec.offsets[j].copy(), np.eye(3)
            for ch, v in zip(chans, row[col : col + len(chans)], strict=True):
                if ch.lower().endswith("position"):
                    t["XYZ".index(ch[0].upper())] = v
                else:
                    rot = rot @ _axis_matrix(ch[0].upper(), v)
            col += len(chans)
            out[f, j] = t if p < 0 else out[f, p] + glob[p] @ t
            glob.append(rot if p < 0 else glob[p] @ rot)
    return out


def bone_variation(positions: np.ndarray, parents, joints) -> float:
    """Max over joints of (max - min) / mean of the joint-parent distance over frames."""
    worst = 0.0
    for j in joints:
        d = np.linalg.norm(positions[:, j] - positions[:, parents[j]], axis=-1)
        worst = max(worst, float(np.ptp(d) / d.mean()))
    return worst


def round_trip_error(motion: bvh.BVHMotion, tmp_path, name="rt.bvh") -> float:
    again = read_bvh(write_bvh(tmp_path / name, motion))
    assert again.joint_names == motion.joint_names and again.channels == motion.channels
    np.testing.assert_allclose(again.offsets, motion.offsets, atol=1e-6)
    assert again.end_sites.keys() == motion.end_sites.keys()
    return float(np.abs(again.positions() - motion.positions()).max())


def check_file(spec: Spec, values: np.ndarray, text: str, tmp_path) -> bvh.BVHMotion:
    """Parse, compare with the independent FK, check rigid bones and the round trip."""
    motion = parse_bvh(text, "synthetic.bvh")
    assert motion.joint_names == spec.names and motion.channels == spec.channels
    np.testing.assert_array_equal(motion.parents, spec.parents)
    pos = motion.positions()
    ref = reference_positions(spec, values)
    assert np.abs(pos - ref).max() <= 1e-9 * max(1.0, np.abs(ref).max())
    rigid = [j for j in range(1, len(spec.names)) if not any(c.endswith("position") for c in spec.channels[j])]
    var, err = bone_variation(pos, spec.parents, rigid), round_trip_error(motion, tmp_path)
    print(f"\n{motion.num_joints} joints {motion.fps:g} fps: |FK - reference FK| {np.abs(pos - ref).max():.1e}, "
          f"bone variation {var:.1e}, round trip {err:.1e}", end="")  # fmt: skip
    assert var <= 1e-4 and err <= 1e-4
    return motion


CMU_NAMES = [
    "Hips", "LHipJoint", "LeftUpLeg", "LeftLeg", "LeftFoot", "LeftToeBase",
    "RHipJoint", "RightUpLeg", "RightLeg", "RightFoot", "RightToeBase",
    "LowerBack", "Spine", "Spine1", "Neck", "Neck1", "Head",
    "LeftShoulder", "LeftArm", "LeftForeArm", "LeftHand", "LeftFingerBase", "LeftHandIndex1", "LThumb",
    "RightShoulder", "RightArm", "RightForeArm", "RightHand", "RightFingerBase", "RightHandIndex1", "RThumb",
]  # fmt: skip
CMU_PARENTS = [-1, 0, 1, 2, 3, 4, 0, 6, 7, 8, 9, 0, 11, 12, 13, 14, 15,
               13, 17, 18, 19, 20, 21, 20, 13, 24, 25, 26, 27, 28, 27]  # fmt: skip
SMALL_NAMES = [
    "Hips",
    "Spine",
    "Head",
    "LeftUpLeg",
    "LeftLeg",
    "LeftFoot",
    "RightUpLeg",
    "RightLeg",
    "RightFoot",
]
SMALL_PARENTS = [-1, 0, 1, 0, 3, 4, 0, 6, 7]


def cmu_spec(seed=0) -> Spec:
    zyx = ("Zrotation", "Yrotation", "Xrotation")
    return make_spec(CMU_NAMES, CMU_PARENTS, ("Xposition", "Yposition", "Zposition", *zyx), zyx, seed)


# ---- files from other sources ------------------------------------------------------------------------------
def test_cmu_style_file(tmp_path):
    spec = cmu_spec()
    values = smooth_values(spec, 60)
    motion = check_file(spec, values, bvh_text(spec, values, 0.008333), tmp_path)
    assert motion.fps == 120 and motion.num_frames == 60 and motion.num_joints == 31
    skel = motion.skeleton()
    assert skel.name == "synthetic" and skel.foot_joints == ((4, 5), (9, 10))


def test_six_channels_on_every_joint(tmp_path):
    spec = make_spec(SMALL_NAMES, SMALL_PARENTS, ROOT6, ROOT6, seed=2)
    values = smooth_values(spec, 40, seed=3)
    motion = check_file(spec, values, bvh_text(spec, values, 1 / 30), tmp_path)
    # the position channels, not the OFFSETs, are the translations
    np.testing.assert_allclose(motion.translations[:, 4], values[:, 24:27])


@pytest.mark.parametrize("order", ["XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX"])
def test_every_euler_order(order, tmp_path):
    rot = tuple(f"{a}rotation" for a in order)
    spec = make_spec(SMALL_NAMES, SMALL_PARENTS, ("Xposition", "Yposition", "Zposition", *rot), rot, seed=4)
    values = smooth_values(spec, 40, seed=5)
    check_file(spec, values, bvh_text(spec, values, 1 / 60), tmp_path)


def test_positions_after_rotations_and_partial_channels(tmp_path):
    spec = make_spec(SMALL_NAMES, SMALL_PARENTS, ("Zrotation", "Xrotation", "Yrotation", *ROOT6[:3]), ZXY, seed=6)
    spec.channels[1] = ("Yrotation", "Xposition", "Zposition", "Xrotation", "Yposition", "Zrotation")  # mixed
    spec.channels[2] = ("Xrotation",)  # one axis
    spec.channels[4] = ("Zrotation", "Yrotation")  # two axes
    spec.channels[5] = ()  # no channels
    spec.channels[7] = ("Xposition", "Yposition", "Zposition")  # positions only
    values = smooth_values(spec, 40, seed=7)
    motion = check_file(spec, values, bvh_text(spec, values, 1 / 30), tmp_path)
    np.testing.assert_allclose(motion.rotations[:, 5], [[1, 0, 0, 0]] * 40)


@pytest.mark.parametrize("brace_inline", [False, True])
def test_tab_indented_crlf_file_with_end_sites(brace_inline, tmp_path):
    spec = make_spec(SMALL_NAMES, SMALL_PARENTS, ROOT6, ZXY, seed=8)
    values = smooth_values(spec, 30, seed=9)
    text = bvh_text(spec, values, 0.0333333, indent="\t", newline="\r\n", brace_inline=brace_inline)
    motion = check_file(spec, values, text, tmp_path)
    assert sorted(motion.end_sites) == [2, 5, 8]
    for j, site in spec.end_sites.items():
        np.testing.assert_array_equal(motion.end_sites[j], site)
    assert read_bvh(write_bvh(tmp_path / "e.bvh", motion)).end_sites.keys() == motion.end_sites.keys()


def test_channel_names_are_case_insensitive_and_kept():
    spec = make_spec(SMALL_NAMES[:3], SMALL_PARENTS[:3], ROOT6, ("ZROTATION", "xrotation", "Yrotation"))
    values = smooth_values(spec, 5)
    motion = parse_bvh(bvh_text(spec, values, 0.1))
    assert motion.channels[1] == ("ZROTATION", "xrotation", "Yrotation")
    assert np.abs(motion.positions() - reference_positions(spec, values)).max() < 1e-9


def test_fps_snaps_to_integers():
    spec = make_spec(SMALL_NAMES[:2], SMALL_PARENTS[:2], ROOT6, ZXY)
    values = smooth_values(spec, 3)
    fps = {ft: parse_bvh(bvh_text(spec, values, ft)).fps for ft in (0.0333333, 0.008333, 0.01, 0.0416667, 0.0123)}
    assert fps == {0.0333333: 30, 0.008333: 120, 0.01: 100, 0.0416667: 24, 0.0123: pytest.approx(1 / 0.0123)}


def test_resample_120_to_20_and_upsampling():
    spec = cmu_spec(seed=3)
    values = smooth_values(spec, 121, seed=4)
    motion = parse_bvh(bvh_text(spec, values, 0.008333))
    down = motion.resample(20)
    assert down.num_frames == 21 and down.fps == 20
    np.testing.assert_allclose(down.positions(), motion.positions()[::6], atol=1e-6)
    up = motion.slice(0, 31).resample(240)
    assert up.num_frames == 61
    np.testing.assert_allclose(up.positions()[::2], motion.positions()[:31], atol=1e-6)
    mid = up.positions()[1::2]  # halfway frames lie between their neighbours for smooth motion
    assert np.abs(mid - 0.5 * (motion.positions()[:30] + motion.positions()[1:31])).max() < 1.0


def test_scaled_slice_and_skeleton():
    spec = make_spec(SMALL_NAMES, SMALL_PARENTS, ROOT6, ZXY)
    motion = parse_bvh(bvh_text(spec, smooth_values(spec, 20), 1 / 30), "walk.bvh")
    metres = motion.scaled(0.01)
    np.testing.assert_allclose(metres.positions(), motion.positions() * 0.01, atol=1e-12)
    np.testing.assert_allclose(metres.end_sites[2], motion.end_sites[2] * 0.01)
    part = motion.slice(5, 15)
    assert part.num_frames == 10
    np.testing.assert_array_equal(part.positions(), motion.positions()[5:15])
    skel = motion.skeleton()
    assert skel.name == "walk" and skel.fps == 30 and skel.foot_joints == ((5,), (8,))


def test_motion_from_arrays_round_trip(tmp_path):
    # parents first but not depth-first (like SMPL's order): the file comes back in depth-first order
    names, parents = ["pelvis", "l_hip", "r_hip", "l_knee", "r_knee"], [-1, 0, 0, 1, 2]
    offsets = np.array([[0, 0.9, 0], [0.1, -0.05, 0], [-0.1, -0.05, 0], [0, -0.4, 0], [0, -0.4, 0]])
    rng = np.random.default_rng(0)
    quats = rng.normal(size=(12, 5, 4))
    quats /= np.linalg.norm(quats, axis=-1, keepdims=True)
    motion = motion_from_arrays(names, parents, offsets, quats, rng.normal(size=(12, 3)), fps=20)
    assert motion.channels[0] == bvh.DEFAULT_ROOT_CHANNELS and motion.channels[1] == bvh.DEFAULT_JOINT_CHANNELS
    assert sorted(motion.end_sites) == [3, 4]
    back = read_bvh(write_bvh(tmp_path / "gen.bvh", motion))
    order = [0, 1, 3, 2, 4]
    assert back.joint_names == [names[j] for j in order] and back.fps == 20
    np.testing.assert_array_equal(back.parents, [-1, 0, 1, 0, 3])
    assert np.abs(back.positions() - motion.positions()[:, order]).max() < 1e-6


def test_a_long_file_parses_every_frame_31_joints():
    """5000 frames of 31 joints parse whole (their speed is a benchmark's business, not an assertion here)."""
    spec = cmu_spec()
    values = np.round(smooth_values(spec, 5000), 6)
    motion = parse_bvh(bvh_text(spec, values, 0.008333))
    assert motion.num_frames == 5000


# ---- the Bandai clips --------------------------------------------------------------------------------------
BANDAI_JOINTS = [
    "joint_Root", "Hips", "Spine", "Chest", "Neck", "Head",
    "Shoulder_L", "UpperArm_L", "LowerArm_L", "Hand_L", "Shoulder_R", "UpperArm_R", "LowerArm_R", "Hand_R",
    "UpperLeg_L", "LowerLeg_L", "Foot_L", "Toes_L", "UpperLeg_R", "LowerLeg_R", "Foot_R", "Toes_R",
]  # fmt: skip


def bandai_clips(zip_path, count=10, seed=0) -> list[tuple[str, str]]:
    with zipfile.ZipFile(zip_path) as zf:
        names = sorted(n for n in zf.namelist() if n.endswith(".bvh"))
        picked = np.random.default_rng(seed).choice(len(names), size=count, replace=False)
        return [(names[i], zf.read(names[i]).decode()) for i in sorted(picked)]


@pytest.mark.shared
@pytest.mark.parametrize("zip_name", ["bandai-ds1.zip", "bandai-ds2.zip"])
def test_bandai_round_trip(zip_name, shared, tmp_path):
    clips = bandai_clips(shared("data", "bandai-namco", zip_name))
    worst = [0.0, 0.0]
    for i, (name, text) in enumerate(clips):
        motion = parse_bvh(text, name)
        assert motion.joint_names == BANDAI_JOINTS and motion.fps == 30
        assert all(c == ROOT6 for c in motion.channels)
        pos = motion.positions()
        assert 100 < np.median(pos[:, 5, 1]) < 200  # head height in centimetres, Y up
        err, var = round_trip_error(motion, tmp_path, f"{i}.bvh"), bone_variation(pos, motion.parents, range(2, 22))
        assert err <= 1e-4 and var <= 1e-4, name
        worst = [max(worst[0], err), max(worst[1], var)]
    print(f"\n{zip_name}: {len(clips)} clips, round trip max |dp| {worst[0]:.1e} cm, bone variation {worst[1]:.1e}")


@pytest.mark.shared
def test_bandai_resample_30_to_20(shared):
    (name, text), *_ = bandai_clips(shared("data", "bandai-namco", "bandai-ds1.zip"), count=1, seed=1)
    motion = parse_bvh(text, name)
    down = motion.resample(20)
    assert down.num_frames == (motion.num_frames - 1) * 20 // 30 + 1
    k = np.arange(0, down.num_frames, 2)  # 1.5 k is an integer
    np.testing.assert_allclose(down.positions()[k], motion.positions()[(3 * k) // 2], atol=1e-6)


# ---- bad input ---------------------------------------------------------------------------------------------
def good_text() -> str:
    spec = make_spec(SMALL_NAMES[:3], SMALL_PARENTS[:3], ROOT6, ZXY)
    return bvh_text(spec, np.round(smooth_values(spec, 10), 4), 1 / 30)


def _motion_cut(text: str) -> str:
    start = text.index("MOTION")
    return text[: start + (len(text) - start) // 2]


BAD_FILES = {
    "truncated": (_motion_cut, ["expected 10 frames x 12 channels = 120 values", "truncated"]),
    "unknown channel": (
        lambda t: t.replace("Xrotation Yrotation", "Foo Yrotation", 1),
        ["line 5", "unknown channel 'Foo'", "Xrotation"],
    ),
    "non-numeric": (lambda t: _replace_value(t, "abc"), ["'abc'", "line 26", "non-numeric"]),
    "missing MOTION": (lambda t: t[: t.index("MOTION")], ["no MOTION"]),
    "data without MOTION": (lambda t: t.replace("MOTION\n", ""), ["expected MOTION", "'Frames:'"]),
    "empty": (lambda t: "  \n", ["empty"]),
    "missing HIERARCHY": (lambda t: t.replace("HIERARCHY\n", ""), ["expected HIERARCHY", "'ROOT'"]),
    "missing ROOT": (lambda t: t.replace("ROOT Hips", "Hips"), ["line 2", "'ROOT <name>'"]),
    "missing brace": (lambda t: t.replace("  }\n", "", 1), ["line 19", "closing joint 'Hips'", "brace"]),
    "extra brace": (lambda t: t.replace("}\nMOTION", "}\n}\nMOTION"), ["more '}' than '{'"]),
    "brace never closed": (lambda t: t[: t.index("MOTION")].rsplit("}", 1)[0], ["'}' closing joint 'Hips'"]),
    "too many values": (lambda t: t.replace("Frames:\t10", "Frames:\t9"), ["more values than 'Frames: 9'"]),
    "zero frame time": (lambda t: _set_frame_time(t, "0"), ["positive"]),
    "negative frame time": (lambda t: _set_frame_time(t, "-0.03"), ["positive"]),
    "NaN": (lambda t: _replace_value(t, "nan"), ["'nan'", "NaN or Inf", "line 26"]),
    "Inf": (lambda t: _replace_value(t, "-inf"), ["'-inf'", "NaN or Inf"]),
    "bad offset": (lambda t: t.replace("OFFSET ", "OFFSET x", 1), ["line 4", "OFFSET of joint 'Hips'"]),
    "channel count": (
        lambda t: t.replace("CHANNELS 3", "CHANNELS 4", 1),
        ["CHANNELS says 4 channels but lists 3"],
    ),
}


def _replace_value(text: str, token: str) -> str:
    lines = text.split("\n")
    row = lines.index("MOTION") + 5  # the 3rd frame
    values = lines[row].split()
    values[7] = token
    lines[row] = " ".join(values)
    return "\n".join(lines)


def _set_frame_time(text: str, value: str) -> str:
    lines = text.split("\n")
    lines[lines.index("MOTION") + 2] = f"Frame Time: {value}"
    return "\n".join(lines)


@pytest.mark.parametrize("case", sorted(BAD_FILES))
def test_bad_files_raise_bvh_error_naming_the_file(case, tmp_path):
    corrupt, expected = BAD_FILES[case]
    path = tmp_path / "walk.bvh"
    path.write_text(corrupt(good_text()))
    with pytest.raises(BVHError) as err:
        read_bvh(path)
    message = str(err.value)
    assert message.startswith(str(path)), message
    for part in expected:
        assert part in message, message


def test_good_text_reads():
    assert parse_bvh(good_text()).num_frames == 10


def test_missing_file_and_folder(tmp_path):
    with pytest.raises(FileNotFoundError, match="nope.bvh: no such BVH file"):
        read_bvh(tmp_path / "nope.bvh")
    with pytest.raises(IsADirectoryError, match="is a folder"):
        read_bvh(tmp_path)


def test_write_errors_leave_nothing_behind(tmp_path, monkeypatch):
    motion = parse_bvh(good_text())
    blocker = tmp_path / "blocker"
    blocker.write_text("a file")
    with pytest.raises(NotADirectoryError, match="blocker is a file, not a folder"):
        write_bvh(blocker / "out.bvh", motion)
    with pytest.raises(IsADirectoryError, match="it is a folder"):
        write_bvh(tmp_path, motion)
    with pytest.raises(FileNotFoundError, match="does not exist"):
        write_bvh(tmp_path / "missing" / "out.bvh", motion)

    def broken_replace(src, dst):
        raise OSError("disk full")

    monkeypatch.setattr(bvh.os, "replace", broken_replace)
    with pytest.raises(OSError, match="disk full"):
        write_bvh(tmp_path / "out.bvh", motion)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["blocker"]


def test_format_bvh_precision_and_layout():
    motion = parse_bvh(good_text())
    text = format_bvh(motion, precision=3)
    assert text.startswith("HIERARCHY\nROOT Hips\n{\n  OFFSET 0.5 90 -3\n  CHANNELS 6 Xposition")
    frame = text.split("\n")[text.split("\n").index("MOTION") + 3].split()
    assert len(frame) == 12 and all(len(v.split(".")[1]) == 3 for v in frame)
