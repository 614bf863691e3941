"""Hostile files for test_bounds.py: BVH files on the shipped model's (Bandai) rig with frame-0 of the embedded test
clip as their rest pose (so a root-only file is a standing body and its up axis can be told), zips that declare or
inflate too much, and folders with link loops."""

from __future__ import annotations

import functools
import io
import struct
import threading
import zipfile
from pathlib import Path

import numpy as np

from motiondiff.data.datamodules import embedded_data_root
from motiondiff.data.formats.bvh import DEFAULT_JOINT_CHANNELS, DEFAULT_ROOT_CHANNELS, format_bvh, motion_from_arrays
from motiondiff.data.formats.prepared import load_split
from motiondiff.data.formats.up_axis import rotation_to_y_up
from motiondiff.geometry.kinematics import forward_kinematics

CLIP_ID = "dataset-1_walk_active_001"
_LOCK = threading.Lock()


@functools.cache
def _rig() -> tuple[list[str], np.ndarray, np.ndarray]:
    """(joint names, parents, frame-0 world positions in cm) of the embedded test clip."""
    data = load_split(embedded_data_root(), "test")
    i = [str(c) for c in data.arrays["ids"]].index(CLIP_ID)
    a, s = data.arrays, data.clip_slice(i)
    parents = np.asarray(a["native_parents"], dtype=np.int64)
    trans = np.broadcast_to(a["native_offsets"][i].astype(np.float64), (1, len(parents), 3)).copy()
    trans[0, 0] = a["native_root"][s][0]
    world = forward_kinematics(a["native_rotations"][s][:1].astype(np.float64), trans, parents)[0][0]
    return [str(n) for n in a["native_joint_names"]], parents, world * 100


def bvh_text(frames: int = 4, frame_time: float = 1 / 120, up: str = "+y", all_channels: bool = False,
             fmt: str = "%.2f") -> str:  # fmt: skip
    """A BVH of the standing pose swaying 1 m forward and back (root channels only, unless `all_channels`: zero rotation
    channels on every joint too), its axes turned so its head points along `up`; values written with `fmt`."""
    names, parents, world = _rig()
    offsets = world - np.where(parents[:, None] >= 0, world[np.maximum(parents, 0)], 0.0)
    to_file = rotation_to_y_up(up)  # y_up = R @ file, so file rows = y_up rows @ R
    joint = DEFAULT_JOINT_CHANNELS if all_channels else ()
    channels = [DEFAULT_ROOT_CHANNELS] + [joint] * (len(names) - 1)
    one = motion_from_arrays(names, parents, offsets @ to_file, np.tile([1.0, 0, 0, 0], (1, len(names), 1)),
                             np.zeros((1, 3)), fps=1 / frame_time, channels=channels)  # fmt: skip
    head = format_bvh(one).split("MOTION")[0]
    t = np.arange(frames) * frame_time
    sway = world[0, 2] + 100 * np.sin(t / 2)
    root = np.stack([np.full(frames, world[0, 0]), np.full(frames, world[0, 1]), sway], 1) @ to_file
    table = np.zeros((frames, sum(len(c) for c in channels)))
    table[:, :3] = root
    buf = io.StringIO()
    np.savetxt(buf, table, fmt=fmt)
    return f"{head}MOTION\nFrames: {frames}\nFrame Time: {frame_time:.8g}\n{buf.getvalue()}"


def set_line(text: str, prefix: str, line: str) -> str:
    """The BVH text with its line starting with `prefix` ("Frames", "Frame Time") replaced."""
    return "\n".join(line if row.startswith(prefix) else row for row in text.split("\n"))


def write(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


def zip_bomb(path: Path, inflated: int, declared: int | None = None, name: str = "clip.bvh") -> Path:
    """A zip of one member of `inflated` bytes (a BVH header, then spaces), deflated to about 1/1000; `declared`: the
    size its headers claim instead (a lying member)."""
    with _LOCK:  # the cases run in threads: make it once
        raw = _bomb(inflated, name)
    path.write_bytes(raw if declared is None else _declare(raw, declared))
    return path


def npz_bomb(path: Path, declared: int = 2**31) -> Path:
    """An .npz of a small joints array whose member claims to inflate to `declared` bytes."""
    buf = io.BytesIO()
    np.savez_compressed(buf, joints=np.zeros((100, 22, 3), np.float32))
    path.write_bytes(_declare(buf.getvalue(), declared))
    return path


def _declare(raw: bytes, declared: int) -> bytes:
    """A one-member zip whose headers claim `declared` uncompressed bytes."""
    raw = bytearray(raw)
    central = raw.rindex(b"PK\x01\x02")
    raw[22:26] = struct.pack("<I", declared)  # the local header, at 0
    raw[central + 24 : central + 28] = struct.pack("<I", declared)
    return bytes(raw)


@functools.cache
def _bomb(inflated: int, name: str) -> bytes:
    head, chunk, buf = bvh_text(1).encode(), b" " * 2**20, io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z, z.open(name, "w") as member:
        member.write(head)
        for _ in range((inflated - len(head)) // len(chunk)):
            member.write(chunk)
    return buf.getvalue()


def zip_of(path: Path, members: dict[str, str]) -> Path:
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        for name, text in members.items():
            z.writestr(name, text)
    return path
