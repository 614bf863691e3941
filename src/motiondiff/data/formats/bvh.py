"""Read and write BVH motion-capture files of any skeleton: any channel layout, Euler order and units.

A `BVHMotion` keeps the file's hierarchy exactly (names, offsets, per-joint channel lists, End Sites) and the
motion as local quaternions (w, x, y, z) plus local translations, so writing it back reproduces the layout.

Conventions (the usual BVH reading, e.g. Biovision, Blender, CMU):
- a joint's rotation order is the order its rotation channels appear in: 'Zrotation Xrotation Yrotation' means
  R = Rz @ Rx @ Ry (intrinsic, degrees); missing rotation axes are 0, a joint without rotation channels is
  unrotated;
- the local translation is the OFFSET, except that position channels REPLACE the matching OFFSET component
  (the Bandai files put a rest pose in the Hips OFFSET and the real position in its channels);
- the translation is applied before the rotation, wherever the position channels sit in the list.

Errors: every problem in the text raises `BVHError` (a ValueError) naming the file, the line and the fix;
`read_bvh` raises FileNotFoundError / IsADirectoryError for a missing path or a folder.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from motiondiff.data.formats.bvh_parse import VALID_CHANNELS, BVHError, RawBVH, channel_kind, parse_text
from motiondiff.geometry.kinematics import forward_kinematics
from motiondiff.geometry.rotations import (
    euler_to_matrix,
    matrix_to_euler,
    matrix_to_quat,
    qfix,
    qinv,
    qmul,
    qslerp,
    quat_to_matrix,
)
from motiondiff.geometry.skeleton import Skeleton
from motiondiff.runtime.atomic import atomic_write

__all__ = [
    "BVHError",
    "BVHMotion",
    "DEFAULT_JOINT_CHANNELS",
    "DEFAULT_ROOT_CHANNELS",
    "VALID_CHANNELS",
    "continued_end_sites",
    "format_bvh",
    "motion_from_arrays",
    "parse_bvh",
    "read_bvh",
    "write_bvh",
]

DEFAULT_ROOT_CHANNELS = ("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation")
DEFAULT_JOINT_CHANNELS = ("Zrotation", "Xrotation", "Yrotation")
_VALID_LOWER = {v.lower() for v in VALID_CHANNELS}


@dataclass(eq=False)
class BVHMotion:
    joint_names: list[str]
    parents: np.ndarray  # (J,) int, -1 for the root; parents come before their children (file order)
    offsets: np.ndarray  # (J, 3) OFFSET of each joint from its parent, file units
    channels: list[tuple[str, ...]]  # per joint, exact names and order as in the file
    end_sites: dict[int, np.ndarray]  # joint index -> End Site OFFSET
    frame_time: float  # seconds per frame, as written in the file
    rotations: np.ndarray  # (F, J, 4) local quaternions (w, x, y, z), continuous over time
    translations: np.ndarray  # (F, J, 3) local translations (OFFSET with position channels substituted)
    source: str = "<memory>"  # file name, for messages and the default skeleton name

    def __post_init__(self):
        self.joint_names = [str(n) for n in self.joint_names]
        self.parents = np.asarray(self.parents, dtype=np.int64)
        self.offsets = np.asarray(self.offsets, dtype=np.float64)
        self.channels = [tuple(c) for c in self.channels]
        self.end_sites = {int(j): np.asarray(v, dtype=np.float64) for j, v in self.end_sites.items()}
        self.frame_time = float(self.frame_time)
        self.rotations = np.asarray(self.rotations, dtype=np.float64)
        self.translations = np.asarray(self.translations, dtype=np.float64)
        _validate(self)

    @property
    def num_frames(self) -> int:
        return int(self.rotations.shape[0])

    @property
    def num_joints(self) -> int:
        return len(self.joint_names)

    @property
    def fps(self) -> float:
        """1 / frame_time, snapped to an integer within 1e-3 relative (files print 0.0333333 for 30 fps)."""
        raw = 1.0 / self.frame_time
        nearest = round(raw)
        return float(nearest) if nearest > 0 and abs(raw - nearest) <= 1e-3 * raw else raw

    def positions(self) -> np.ndarray:
        """(F, J, 3) world joint positions in the file's units."""
        return forward_kinematics(self.rotations, self.translations, self.parents)[0]

    def skeleton(self, name: str | None = None) -> Skeleton:
        return Skeleton.infer(
            name or Path(self.source).stem or "bvh",
            self.joint_names,
            self.parents,
            self.offsets,
            fps=self.fps,
        )

    def scaled(self, factor: float) -> BVHMotion:
        """Change units (e.g. 0.01 for cm -> m): offsets, translations and End Sites are multiplied."""
        return replace(
            self,
            offsets=self.offsets * factor,
            translations=self.translations * factor,
            end_sites={j: v * factor for j, v in self.end_sites.items()},
        )

    def rotated(self, matrix: np.ndarray) -> BVHMotion:
        """The same motion in turned axes, `matrix` (3, 3) a rotation with new = matrix @ old (e.g.
        `motiondiff.data.formats.up_axis.rotation_to_y_up("+z")` for a Z-up file): a change of basis, so offsets,
        translations and End Sites are turned and every local rotation q becomes r q r^-1. World positions turn
        with it and the rest pose stays the same pose in the new axes. Writing the result keeps each joint's
        channels, which holds a turned rotation exactly only for joints with all three rotation channels."""
        matrix = np.asarray(matrix, dtype=np.float64)
        proper = matrix.shape == (3, 3) and np.allclose(matrix @ matrix.T, np.eye(3), atol=1e-9)
        if not (proper and np.linalg.det(matrix) > 0):
            raise ValueError(f"BVHMotion.rotated: matrix must be a 3x3 rotation (orthonormal, det +1), got {matrix}")
        r = matrix_to_quat(matrix)
        rotations = qmul(qmul(np.broadcast_to(r, self.rotations.shape), self.rotations), qinv(r))
        return replace(
            self,
            offsets=self.offsets @ matrix.T,
            translations=self.translations @ matrix.T,
            end_sites={j: matrix @ v for j, v in self.end_sites.items()},
            rotations=qfix(rotations),
        )

    def slice(self, start: int | None = None, stop: int | None = None) -> BVHMotion:
        frames = slice(start, stop)
        return replace(self, rotations=self.rotations[frames].copy(), translations=self.translations[frames].copy())

    def resampled_frames(self, fps: float) -> int:
        """How many frames `resample(fps)` makes (computed, nothing resampled)."""
        if not fps > 0:
            raise ValueError(f"resample: fps must be positive, got {fps}")
        return int(np.floor((self.num_frames - 1) * fps / self.fps + 1e-9)) + 1 if self.num_frames else 0

    def resample(self, fps: float, window: tuple[int, int] | None = None) -> BVHMotion:
        """Motion at `fps`: frames at times k / fps (k = 0, 1, ...) up to the last source frame, source
        frame i being at i / self.fps; rotations are slerped, translations interpolated linearly. `window`
        (start, stop): only those output frames (the same motion as resampling all and slicing, without the
        memory of the whole clip; quaternion signs may differ)."""
        count, n_out = self.num_frames, self.resampled_frames(fps)
        if count == 0:
            return replace(self, frame_time=1.0 / fps)
        start, stop = (0, n_out) if window is None else (max(int(window[0]), 0), min(int(window[1]), n_out))
        # Source frame index of each output frame, on the snapped fps grid (exact for 30->20, 120->20, ...).
        u = np.arange(start, max(stop, start)) * self.fps / fps
        near = np.round(u)
        u = np.where(np.abs(u - near) < 1e-9, near, u)  # land exactly on coinciding source frames
        i0 = np.minimum(np.floor(u).astype(np.int64), max(count - 2, 0))
        i1 = np.minimum(i0 + 1, count - 1)
        t = u - i0
        rotations = qfix(qslerp(self.rotations[i0], self.rotations[i1], t[:, None]))
        translations = self.translations[i0] + t[:, None, None] * (self.translations[i1] - self.translations[i0])
        return replace(self, frame_time=1.0 / fps, rotations=rotations, translations=translations)


def _validate(m: BVHMotion) -> None:
    j = len(m.joint_names)
    frames = m.rotations.shape[0] if m.rotations.ndim == 3 else -1
    problems = []
    if m.parents.shape != (j,) or (j and m.parents[0] != -1):
        problems.append(f"parents must have shape ({j},) with -1 first, got {m.parents.tolist()}")
    elif any(not 0 <= p < i for i, p in enumerate(m.parents.tolist()[1:], 1)):
        problems.append("joints must be ordered parents first, with a single root")
    if m.offsets.shape != (j, 3):
        problems.append(f"offsets must be ({j}, 3), got {m.offsets.shape}")
    if len(m.channels) != j or any(c.lower() not in _VALID_LOWER for cs in m.channels for c in cs):
        problems.append(f"channels must list {j} tuples of names from {VALID_CHANNELS}")
    if m.rotations.shape != (frames, j, 4) or m.translations.shape != (frames, j, 3):
        problems.append(f"rotations/translations must be (F, {j}, 4)/(F, {j}, 3), got "
                        f"{m.rotations.shape}/{m.translations.shape}")  # fmt: skip
    if any(not 0 <= k < j or v.shape != (3,) for k, v in m.end_sites.items()):
        problems.append("end_sites must map joint indices to 3-vectors")
    if not (np.isfinite(m.frame_time) and m.frame_time > 0):
        problems.append(f"frame_time must be positive, got {m.frame_time}")
    if problems:
        raise ValueError(f"BVHMotion {m.source}: " + "; ".join(problems))


# ---- reading -----------------------------------------------------------------------------------------------
def read_bvh(path: str | os.PathLike) -> BVHMotion:
    """Read a BVH file. BVHError for bad content; FileNotFoundError/IsADirectoryError for a bad path."""
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"{path}: no such BVH file; check the path (relative to {Path.cwd()})")
    if path.is_dir():
        raise IsADirectoryError(f"{path}: is a folder, not a BVH file; pass the path of a .bvh file")
    return parse_bvh(path.read_bytes(), source=str(path))


def parse_bvh(text: str | bytes, source: str = "<string>") -> BVHMotion:
    """Parse BVH text (e.g. a zip member's bytes); `source` names it in error messages."""
    if isinstance(text, bytes):
        try:
            text = text.decode("utf-8")
        except UnicodeDecodeError:  # old exporters write Latin-1 joint names
            text = text.decode("latin-1")
    return _motion_from_raw(parse_text(text, source), source)


def _rotation_axes(channels: tuple[str, ...]) -> str:
    """'Zrotation Xrotation Yrotation' (positions anywhere) -> 'ZXY'."""
    return "".join("XYZ"[axis] for kind, axis in map(channel_kind, channels) if kind == "rotation")


def _full_order(axes: str) -> tuple[str, list[int]]:
    """Euler order for a joint with 1-3 rotation channels, and where the file's axes sit in it. Missing axes
    have angle 0; a single missing axis goes in the middle, whose range (+-90) holds 0 while the outer angles
    cover the whole circle, so converting back gives 0 for it again and dropping it loses nothing."""
    missing = "".join(a for a in "XYZ" if a not in axes)
    order = axes[0] + missing + axes[1] if len(axes) == 2 else axes + missing
    return order, [order.index(a) for a in axes]


def _euler_to_quat(angles: np.ndarray, axes: str) -> np.ndarray:
    order, cols = _full_order(axes)
    full = np.zeros((angles.shape[0], 3))
    full[:, cols] = angles
    return qfix(matrix_to_quat(euler_to_matrix(full, order)))


def _quat_to_euler(quats: np.ndarray, axes: str) -> np.ndarray:
    order, cols = _full_order(axes)
    return matrix_to_euler(quat_to_matrix(quats), order)[:, cols]


def _motion_from_raw(raw: RawBVH, source: str) -> BVHMotion:
    values = raw.values
    offsets = np.array(raw.offsets, dtype=np.float64).reshape(-1, 3)
    frames, joints = values.shape[0], len(raw.names)
    translations = np.repeat(offsets[None], frames, axis=0)
    rotations = np.zeros((frames, joints, 4))
    rotations[..., 0] = 1.0
    col = 0
    for j, chans in enumerate(raw.channels):
        block = values[:, col : col + len(chans)]
        col += len(chans)
        rot_cols = []
        for k, (kind, axis) in enumerate(map(channel_kind, chans)):
            if kind == "position":
                translations[:, j, axis] = block[:, k]
            else:
                rot_cols.append(k)
        if rot_cols and frames:
            rotations[:, j] = _euler_to_quat(block[:, rot_cols], _rotation_axes(chans))
    return BVHMotion(
        raw.names,
        raw.parents,
        offsets,
        raw.channels,
        raw.end_sites,
        raw.frame_time,
        rotations,
        translations,
        source,
    )


# ---- writing -----------------------------------------------------------------------------------------------
def _depth_first(parents: np.ndarray) -> list[int]:
    """BVH nests children inside parents, so the file (and its channel columns) follow a depth-first order."""
    children: list[list[int]] = [[] for _ in parents]
    for i, p in enumerate(parents.tolist()):
        if p >= 0:
            children[p].append(i)
    order, stack = [], [0]
    while stack:
        j = stack.pop()
        order.append(j)
        stack.extend(reversed(children[j]))
    return order


def _number(v: float, precision: int) -> str:
    return np.format_float_positional(float(v), precision=precision, trim="-")


def _hierarchy_lines(m: BVHMotion, precision: int) -> list[str]:
    lines = ["HIERARCHY"]
    depth = {-1: -1}
    open_joints: list[int] = []  # joints whose '}' is still to be written

    def close_until(parent: int) -> None:
        while open_joints and open_joints[-1] != parent:
            j = open_joints.pop()
            ind = "  " * depth[j]
            if j in m.end_sites:
                off = " ".join(_number(v, precision) for v in m.end_sites[j])
                lines.extend([f"{ind}  End Site", f"{ind}  {{", f"{ind}    OFFSET {off}", f"{ind}  }}"])
            lines.append(f"{ind}}}")

    for j in _depth_first(m.parents):
        parent = int(m.parents[j])
        close_until(parent)
        depth[j] = depth[parent] + 1
        ind = "  " * depth[j]
        lines.extend([f"{ind}{'ROOT' if parent < 0 else 'JOINT'} {m.joint_names[j]}", f"{ind}{{"])
        lines.append(f"{ind}  OFFSET {' '.join(_number(v, precision) for v in m.offsets[j])}")
        if m.channels[j]:
            lines.append(f"{ind}  CHANNELS {len(m.channels[j])} {' '.join(m.channels[j])}")
        open_joints.append(j)
    close_until(-1)
    return lines


def _channel_table(m: BVHMotion) -> np.ndarray:
    """(F, C) channel values in the file's column order: Euler angles in each joint's own order, positions."""
    columns = []
    for j in _depth_first(m.parents):
        axes = _rotation_axes(m.channels[j])
        euler = _quat_to_euler(m.rotations[:, j], axes) if axes and m.num_frames else None
        for kind, axis in map(channel_kind, m.channels[j]):
            if kind == "position":
                columns.append(m.translations[:, j, axis])
            else:
                columns.append(euler[:, axes.index("XYZ"[axis])] if euler is not None else np.zeros(0))
    return np.stack(columns, axis=1) if columns else np.zeros((m.num_frames, 0))


def format_bvh(motion: BVHMotion, precision: int = 6) -> str:
    """BVH text of `motion` (joints written depth-first; a motion read from a file keeps its order)."""
    table = _channel_table(motion)
    row = " ".join([f"%.{precision}f"] * table.shape[1])
    lines = _hierarchy_lines(motion, precision)
    lines += ["MOTION", f"Frames: {motion.num_frames}", f"Frame Time: {motion.frame_time:.8g}"]
    lines += [row % tuple(r) for r in table.tolist()]
    return "\n".join(lines) + "\n"


def _check_target(path: Path) -> None:
    if path.is_dir():
        raise IsADirectoryError(f"cannot write {path}: it is a folder; give a file path such as {path / 'clip.bvh'}")
    for folder in path.parents:
        if folder.exists():
            if not folder.is_dir():
                raise NotADirectoryError(
                    f"cannot write {path}: {folder} is a file, not a folder; choose another output path"
                )
            if folder != path.parent:
                raise FileNotFoundError(f"cannot write {path}: folder {path.parent} does not exist; create it first")
            return


def write_bvh(path: str | os.PathLike, motion: BVHMotion, precision: int = 6) -> Path:
    """Write `motion` atomically (temp file in the same folder, then os.replace), so a failed write leaves
    nothing. `precision` decimals for every value (6 keeps round-trip positions far below 1e-4 file units).
    Raises IsADirectoryError / NotADirectoryError / FileNotFoundError for an unusable path."""
    path = Path(path)
    _check_target(path)
    text = format_bvh(motion, precision)
    return atomic_write(path, lambda tmp: Path(tmp).write_text(text, encoding="utf-8", newline="\n"), suffix=".bvh")


# ---- building from arrays ----------------------------------------------------------------------------------
def motion_from_arrays(
    joint_names,
    parents,
    offsets,
    rotations,
    translations,
    fps: float,
    channels=None,
    end_sites: dict[int, np.ndarray] | None = None,
    source: str = "<generated>",
) -> BVHMotion:
    """A BVHMotion from local quaternions (F, J, 4) and translations: (F, J, 3), or (F, 3) root positions
    with the other joints at their offsets. Default channels: root 'Xposition Yposition Zposition Zrotation
    Xrotation Yrotation', others 'Zrotation Xrotation Yrotation'. Leaves get an End Site that continues their
    own bone by its length (`continued_end_sites`; animation tools warn about zero-length End Sites) unless
    end_sites is given (`Skeleton.end_sites` has anatomical ones). Non-root translations are only kept where a
    joint has position channels."""
    parents = np.asarray(parents, dtype=np.int64)
    offsets = np.asarray(offsets, dtype=np.float64)
    rotations = np.asarray(rotations, dtype=np.float64)
    translations = np.asarray(translations, dtype=np.float64)
    if translations.ndim == 2:
        full = np.repeat(offsets[None], translations.shape[0], axis=0)
        full[:, 0] = translations
        translations = full
    if channels is None:
        channels = [DEFAULT_ROOT_CHANNELS if p < 0 else DEFAULT_JOINT_CHANNELS for p in parents.tolist()]
    if end_sites is None:
        end_sites = continued_end_sites(parents, offsets)
    return BVHMotion(
        list(joint_names), parents, offsets, channels, end_sites, 1.0 / fps, rotations, translations, source
    )


def continued_end_sites(parents, offsets) -> dict[int, np.ndarray]:
    """End Site of every leaf joint continuing its bone: the leaf's own OFFSET again (its parent's where the leaf's
    is zero; 0.1 of the longest bone along +Y where both are). Never zero for a skeleton with any bone."""
    parents = np.asarray(parents, dtype=np.int64)
    offsets = np.asarray(offsets, dtype=np.float64)
    lengths = np.linalg.norm(offsets, axis=-1)
    tiny = 1e-9 * max(float(lengths.max(initial=0.0)), 1e-12)
    sites = {}
    for leaf in sorted(set(range(len(parents))) - set(parents.tolist())):
        bone = next((j for j in (leaf, int(parents[leaf])) if j >= 0 and lengths[j] > tiny), None)
        if bone is not None:
            sites[leaf] = offsets[bone].copy()
        else:
            sites[leaf] = np.array([0.0, 0.1 * float(lengths.max(initial=0.0)) or 0.1, 0.0])
    return sites
