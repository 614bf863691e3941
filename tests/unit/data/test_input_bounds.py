"""Bounds on what small inputs may ask for: BVH frame time, frame and value counts, duplicate joint names, the frames
a clip resamples to (and resampling only a window), zip members that declare or inflate too much, symlinked source
folders, and the up axis of the files `prepare bvh` reads."""

from __future__ import annotations

import os
import struct
import zipfile

import numpy as np
import pytest
from test_bvh import ROOT6, ZXY, bvh_text, make_spec, smooth_values
from test_prepare_bvh import write_bvh as write_walk

from motiondiff.data.formats import archive
from motiondiff.data.formats.archive import Source, SourceError
from motiondiff.data.formats.array_bounds import check_array_file
from motiondiff.data.formats.bvh import BVHError, motion_from_arrays, parse_bvh, read_bvh, write_bvh
from motiondiff.data.formats.bvh_parse import MAX_DEPTH, MAX_FRAME_JOINTS, MAX_FRAMES, MAX_JOINTS, MAX_VALUES
from motiondiff.data.formats.prepared import load_split
from motiondiff.data.formats.up_axis import rotation_to_y_up
from motiondiff.data.preparing.from_bvh import prepare_bvh
from motiondiff.data.preparing.processing import MAX_RESAMPLED_FRAMES, ClipError, process_motion
from motiondiff.data.preparing.writer import PrepareError

NAMES, PARENTS = ["Hips", "Spine", "Head", "LeftLeg", "RightLeg"], [-1, 0, 1, 0, 0]


def small_bvh(frames=10, frame_time=0.05, names=NAMES, parents=PARENTS) -> str:
    spec = make_spec(names, parents, ROOT6, ZXY)
    return bvh_text(spec, smooth_values(spec, frames), frame_time)


def _with_line(text: str, prefix: str, line: str) -> str:
    return "\n".join(line if row.startswith(prefix) else row for row in text.split("\n"))


@pytest.mark.parametrize("value", ["1000000", "11", "0.00005"])
def test_frame_time_outside_its_range_is_refused(value):
    with pytest.raises(BVHError, match=r"clip\.bvh: line \d+: 'Frame Time: .*' seconds per frame is outside "
                                       r"0\.0001\.\.10 s; write the seconds per frame"):  # fmt: skip
        parse_bvh(_with_line(small_bvh(), "Frame Time", f"Frame Time: {value}"), source="clip.bvh")


def test_frame_time_at_the_bounds_is_read():
    for value in ("0.0001", "10"):
        assert parse_bvh(_with_line(small_bvh(), "Frame Time", f"Frame Time: {value}")).frame_time == float(value)


def test_frame_counts_beyond_the_bounds_are_refused_before_the_data_is_read():
    many = _with_line(small_bvh(), "Frames", f"Frames: {MAX_FRAMES + 1}")
    with pytest.raises(BVHError, match=rf"'Frames: {MAX_FRAMES + 1}' x 18 channels x 5 joints is more than .*shorter"):
        parse_bvh(many, source="clip.bvh")
    chain = small_bvh(names=[f"J{i}" for i in range(21)], parents=list(range(-1, 20)))  # 66 channels
    wide = MAX_VALUES // 66 + 1  # within MAX_FRAMES, beyond MAX_VALUES
    with pytest.raises(BVHError, match=rf"'Frames: {wide}' x 66 channels .*{MAX_VALUES} values"):
        parse_bvh(_with_line(chain, "Frames", f"Frames: {wide}"), source="clip.bvh")
    spec = make_spec([f"J{i}" for i in range(21)], list(range(-1, 20)), ROOT6, ())  # 6 channels, 21 joints
    deep = MAX_FRAME_JOINTS // 21 + 1  # within MAX_FRAMES and MAX_VALUES, beyond frames x joints
    with pytest.raises(BVHError, match=rf"'Frames: {deep}' x 6 channels x 21 joints .*{MAX_FRAME_JOINTS} frames x j"):
        parse_bvh(_with_line(bvh_text(spec, smooth_values(spec, 2), 0.05), "Frames", f"Frames: {deep}"))


def test_declared_frames_must_match_the_data():
    with pytest.raises(BVHError, match=r"more values than 'Frames: 9'"):
        parse_bvh(_with_line(small_bvh(10), "Frames", "Frames: 9"))
    with pytest.raises(BVHError, match=r"truncated"):
        parse_bvh(_with_line(small_bvh(10), "Frames", "Frames: 11"))
    blank = small_bvh(1)
    blank = blank[: blank.index("Frame Time")] + "Frame Time: 0.05\n   \n"  # whitespace only (numpy reads -1)
    with pytest.raises(BVHError, match=r"found 0"):
        parse_bvh(blank)


@pytest.mark.parametrize("bad", ["abc", "1_000", "0x10"])
def test_a_bad_value_is_named_with_its_line(bad):
    text = small_bvh(5)
    lines = text.split("\n")
    row = lines.index("Frame Time:\t0.05") + 3
    lines[row] = lines[row].replace(lines[row].split()[2], bad, 1)
    with pytest.raises(BVHError, match=rf"line {row + 1}: non-numeric value '{bad}'"):
        parse_bvh("\n".join(lines))


def test_duplicate_joint_names_are_refused():
    with pytest.raises(BVHError, match=r"clip\.bvh: line \d+: joint name 'Spine' appears twice.*rename one"):
        parse_bvh(small_bvh(names=["Hips", "Spine", "Head", "Spine", "RightLeg"]), source="clip.bvh")


def _chain(count: int, nested: bool) -> str:
    """A skeleton of `count` joints below the root, each inside the one before (nested) or all beside each other."""
    if nested:
        body = "".join(f"JOINT j{i}\n{{\nOFFSET 0 1 0\n" for i in range(count)) + "}\n" * count
    else:
        body = "".join(f"JOINT j{i}\n{{\nOFFSET 0 1 0\n}}\n" for i in range(count))
    return f"HIERARCHY\nROOT a\n{{\nOFFSET 0 0 0\n{body}}}\nMOTION\nFrames: 1\nFrame Time: 0.1\n\n"


def test_skeletons_too_large_or_too_deep_are_refused():
    assert parse_bvh(_chain(150, nested=True)).num_joints == 151
    for count, nested in ((MAX_DEPTH + 1, True), (MAX_JOINTS, False)):  # (Python's recursion would end the first)
        with pytest.raises(BVHError, match=rf"more than {MAX_JOINTS} joints, or joints nested more than {MAX_DEPTH}"):
            parse_bvh(_chain(count, nested))


def test_resampling_a_window_gives_the_frames_of_the_whole():
    motion = parse_bvh(small_bvh(frames=200, frame_time=1 / 120))
    whole = motion.resample(20.0)
    assert motion.resampled_frames(20.0) == whole.num_frames == 34
    part = motion.resample(20.0, (7, 19))
    assert part.num_frames == 12
    np.testing.assert_allclose(part.positions(), whole.positions()[7:19], atol=1e-9)
    assert motion.resample(20.0, (30, 99)).num_frames == 4  # clipped to the motion


def test_a_clip_resampled_beyond_the_bound_is_refused():
    rot = np.tile([1.0, 0, 0, 0], (20002, 1, 1))
    motion = motion_from_arrays(["Hips"], [-1], np.zeros((1, 3)), rot, np.zeros((20002, 3)), fps=0.1)
    assert motion.resampled_frames(20.0) > MAX_RESAMPLED_FRAMES
    with pytest.raises(ClipError, match=rf"more than {MAX_RESAMPLED_FRAMES} frames or"):
        process_motion(motion, None)


# ---- zip members ------------------------------------------------------------------------------------------------
def _zip(path, name: str, data: bytes, declared: int | None = None):
    """A zip of one deflated member; `declared`: the uncompressed size its headers claim instead of the real one."""
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr(name, data)
    if declared is not None:
        raw = bytearray(path.read_bytes())
        local, central = raw.index(b"PK\x03\x04"), raw.rindex(b"PK\x01\x02")
        raw[local + 22 : local + 26] = struct.pack("<I", declared)
        raw[central + 24 : central + 28] = struct.pack("<I", declared)
        path.write_bytes(bytes(raw))
    return path


def test_a_member_declaring_too_much_is_refused(tmp_path, monkeypatch):
    monkeypatch.setattr(archive, "MAX_MEMBER_BYTES", 1000)
    src = Source(_zip(tmp_path / "big.zip", "a.bvh", b"0 " * 1000))
    with pytest.raises(SourceError, match=r"big\.zip: member a\.bvh declares 0 MB uncompressed, more than"):
        src.read_bytes("a.bvh")


def test_a_member_inflating_beyond_its_declared_size_is_refused(tmp_path):
    src = Source(_zip(tmp_path / "bomb.zip", "a.bvh", b"0 " * 100000, declared=100))
    with pytest.raises(SourceError, match=r"member a\.bvh does not inflate to the 100 bytes it declares .*zip bomb"):
        src.read_bytes("a.bvh")
    assert Source(_zip(tmp_path / "ok.zip", "a.bvh", b"0 " * 10)).read_bytes("a.bvh") == b"0 " * 10


# ---- folders with links -----------------------------------------------------------------------------------------
def test_a_symlinked_folder_is_followed(tmp_path):
    (tmp_path / "elsewhere").mkdir()
    (tmp_path / "elsewhere" / "b.bvh").write_text("x")
    (tmp_path / "src").mkdir()
    (tmp_path / "src" / "a.bvh").write_text("x")
    os.symlink(tmp_path / "elsewhere", tmp_path / "src" / "linked")
    assert Source(tmp_path / "src").names() == ["a.bvh", "linked/b.bvh"]


def test_a_link_loop_and_a_broken_link_are_refused(tmp_path):
    (tmp_path / "src" / "sub").mkdir(parents=True)
    (tmp_path / "src" / "sub" / "a.bvh").write_text("x")
    os.symlink(tmp_path / "src", tmp_path / "src" / "sub" / "up")
    with pytest.raises(SourceError, match=r"is a link to a folder already read \(a link loop"):
        Source(tmp_path / "src")
    os.unlink(tmp_path / "src" / "sub" / "up")
    os.symlink(tmp_path / "nowhere", tmp_path / "src" / "gone.bvh")
    with pytest.raises(SourceError, match=r"gone\.bvh is a broken link"):
        Source(tmp_path / "src")


# ---- up axis in prepare -----------------------------------------------------------------------------------------
def test_prepare_turns_z_up_files_to_y_up(tmp_path):
    (tmp_path / "z").mkdir()
    for i in range(10):
        write_walk(tmp_path / "y" / f"w{i}.bvh", seed=i)
        motion = read_bvh(tmp_path / "y" / f"w{i}.bvh")
        write_bvh(tmp_path / "z" / f"w{i}.bvh", motion.rotated(rotation_to_y_up("+z").T))
    y = prepare_bvh([tmp_path / "y"], tmp_path / "out_y", workers=1, progress=False)
    z = prepare_bvh([tmp_path / "z"], tmp_path / "out_z", workers=1, progress=False)
    assert y["up_axes"] == {"+y": 10} and z["up_axes"] == {"+z": 10} and z["clips"] == y["clips"]
    for split in ("train", "test"):
        a, b = load_split(tmp_path / "out_y", split).arrays, load_split(tmp_path / "out_z", split).arrays
        np.testing.assert_allclose(a["joints"], b["joints"], atol=1e-4)
    forced = prepare_bvh([tmp_path / "z"], tmp_path / "out_f", workers=1, progress=False, up_axis="y")
    assert forced["up_axes"] == {"+y": 10}  # forced: read as it says, the body lies down
    with pytest.raises(PrepareError, match=r"--up-axis: .*'w'"):
        prepare_bvh([tmp_path / "z"], tmp_path / "out_w", workers=1, progress=False, up_axis="w")


@pytest.mark.parametrize("name", ["../evil.bvh", "/tmp/evil.bvh", "a/../../evil.bvh", "C:/evil.bvh"])
def test_a_member_named_outside_the_archive_is_refused(tmp_path, name):
    with pytest.raises(SourceError, match=r"points outside the archive"):
        Source(_zip(tmp_path / "trav.zip", name, b"x"))


# ---- .npy / .npz motion files -----------------------------------------------------------------------------------
def test_array_files_asking_for_too_much_are_refused_from_their_headers(tmp_path):
    big = tmp_path / "big.npy"
    with open(big, "wb") as f:  # a header declaring 10^9 frames, and no data
        np.lib.format.write_array_header_1_0(f, {"descr": "<f4", "fortran_order": False, "shape": (10**9, 22, 3)})
    with pytest.raises(ValueError, match=r"big\.npy: its array takes 251770 MB, more than the 256 MB"):
        check_array_file(big)
    np.save(tmp_path / "ok.npy", np.zeros((10, 22, 3), np.float32))
    np.savez_compressed(tmp_path / "ok.npz", joints=np.zeros((1000, 22, 3), np.float32))
    check_array_file(tmp_path / "ok.npy")
    check_array_file(tmp_path / "ok.npz")
    with pytest.raises(ValueError, match=r"ok\.npz: joints\.npy takes 0 MB, more than the 0 MB"):
        check_array_file(tmp_path / "ok.npz", limit=1000)
