"""Join real clips into one multi-action motion, and their captions into one caption (pure functions).

A clip is split into a path on the ground (x, z) of its anchor, the mean of the feet, a heading (yaw) and a pose
relative to the anchor in the heading frame. The joined motion integrates the clips' own per-frame anchor steps and
turns, so each next clip starts where the previous one is and faces where it faces (a rotation about the vertical
axis plus a translation on the ground). Anchoring the feet rather than the pelvis matters when two standing clips
have different stances: the body then shifts over the feet instead of the feet sliding under the body. Consecutive
clips overlap by `transition` frames in which poses (bone by bone), steps and turns are cross-faded with a
smooth-step weight: the root never jumps or slides back, and the pose moves from one clip to the next within the
transition. Outside the transitions every frame is its clip's frame, rigidly moved. Native rotations (the rig of the prepared
data) are moved by the same rigid motion and slerped with the same weights, so joints and rig stay one motion.

`motiondiff.data.compositional.dataset` builds the datasets from these functions.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter1d

from motiondiff.data.preparing.captions import SUBJECTS
from motiondiff.data.representations.hml_features import canonicalize_joints, ground_and_face
from motiondiff.geometry.kinematics import forward_kinematics
from motiondiff.geometry.rotations import qmul, qrot, qslerp
from motiondiff.geometry.skeleton import SMPL22, Skeleton

# Heading smoothing (frames at 20 fps): a walker's torso twists about 10 degrees each step; aligning the next clip
# to one twisted frame would send it off at that angle. Outside transitions the choice does not matter (exact).
HEADING_SIGMA = 4.0
UP = np.array([0.0, 1.0, 0.0])


@dataclass
class Part:
    """One clip (or a window of it), canonical SMPL-22 joints and optionally its native rig motion."""

    joints: np.ndarray  # (N, 22, 3)
    rotations: np.ndarray | None = None  # (N, J, 4) local quaternions of the native rig
    root: np.ndarray | None = None  # (N, 3) native root position


@dataclass
class Joined:
    joints: np.ndarray  # (F, 22, 3) float64, not yet re-canonicalised
    rotations: np.ndarray | None  # (F, J, 4)
    root: np.ndarray | None  # (F, 3)
    frames: list[tuple[int, int]]  # each part's [start, stop) in the joined motion; neighbours share `transition`


def smoothstep(n: int) -> np.ndarray:
    """(n,) cross-fade weights of the next clip, strictly inside (0, 1), with zero slope at both ends."""
    x = (np.arange(n) + 1.0) / (n + 1.0)
    return x * x * (3.0 - 2.0 * x)


def heading(joints: np.ndarray, skeleton: Skeleton = SMPL22, sigma: float = HEADING_SIGMA) -> np.ndarray:
    """(N,) unwrapped yaw of the body's forward direction (0 = +Z, positive towards +X), from hips and shoulders
    as HumanML3D's placement reads it, smoothed over `sigma` frames."""
    r_hip, l_hip, r_sdr, l_sdr = skeleton.face_joints
    across = (joints[:, r_hip] - joints[:, l_hip]) + (joints[:, r_sdr] - joints[:, l_sdr])
    forward = np.cross(UP, across)[:, [0, 2]]
    if sigma > 0 and len(forward) > 1:
        forward = gaussian_filter1d(forward, sigma, axis=0, mode="nearest")
    return np.unwrap(np.arctan2(forward[:, 0], forward[:, 1]))


def yaw_matrix(yaw: np.ndarray) -> np.ndarray:
    """(..., 3, 3) rotations about +Y by `yaw` (turns +Z towards +X)."""
    c, s = np.cos(yaw), np.sin(yaw)
    o, i = np.zeros_like(yaw), np.ones_like(yaw)
    return np.stack([np.stack([c, o, s], -1), np.stack([o, i, o], -1), np.stack([-s, o, c], -1)], -2)


def yaw_quat(yaw: np.ndarray) -> np.ndarray:
    """(..., 4) quaternions (w, x, y, z) of yaw_matrix."""
    return np.stack([np.cos(yaw / 2), np.zeros_like(yaw), np.sin(yaw / 2), np.zeros_like(yaw)], -1)


@dataclass
class _Local:
    """A part in its own moving heading frame: everything a join needs, free of where the clip was placed."""

    pose: np.ndarray  # (N, 22, 3) joints relative to the anchor (feet mean on the ground), heading frame; y kept
    step: np.ndarray  # (N, 2) anchor step to the next frame, in this frame's heading frame (last repeated)
    turn: np.ndarray  # (N,) heading change to the next frame (last repeated)
    root_rot: np.ndarray | None  # (N, 4) native root rotation in the heading frame
    root: np.ndarray | None  # (N, 3) native root relative to the anchor, heading frame


def _localise(part: Part) -> _Local:
    j = np.asarray(part.joints, dtype=np.float64)
    if len(j) < 2:
        raise ValueError(f"a part needs at least 2 frames, got {len(j)}")
    yaw = heading(j)
    ground = _anchor(j)
    inv = yaw_matrix(-yaw)
    pose = np.einsum("nab,njb->nja", inv, j - ground[:, None])
    delta = np.diff(ground, axis=0)
    step = np.einsum("nab,nb->na", inv[:-1], delta)[:, [0, 2]]
    step = np.concatenate([step, step[-1:]])
    turn = np.diff(yaw)
    turn = np.concatenate([turn, turn[-1:]])
    root_rot = root = None
    if part.rotations is not None:
        root_rot = qmul(yaw_quat(-yaw), np.asarray(part.rotations[:, 0], dtype=np.float64))
        root = np.einsum("nab,nb->na", inv, np.asarray(part.root, dtype=np.float64) - ground)
    return _Local(pose, step, turn, root_rot, root)


def join_parts(parts: list[Part], transition: int) -> Joined:
    """Join parts in order; each next part overlaps the previous one's last `transition` frames (see module doc).
    The first part keeps its placement exactly; the joined motion has sum(len) - (len(parts)-1) * transition frames."""
    if not parts:
        raise ValueError("nothing to join")
    lengths = [len(p.joints) for p in parts]
    if transition < 1 or any(n < 2 * transition + 1 for n in lengths[1:-1]) or min(lengths) <= transition:
        raise ValueError(f"transition of {transition} frames does not fit parts of {lengths} frames")
    rig = parts[0].rotations is not None
    local = [_localise(p) for p in parts]
    starts = np.concatenate([[0], np.cumsum(lengths[:-1]) - transition * np.arange(1, len(parts))])
    total = int(starts[-1] + lengths[-1])
    frames = [(int(s), int(s + n)) for s, n in zip(starts, lengths, strict=True)]

    def fill(get, blend=_lerp):
        """One array over the joined timeline: each part's values, cross-faded where two overlap."""
        out = None
        for k, ((s, e), loc) in enumerate(zip(frames, local, strict=True)):
            values = get(loc, parts[k])
            if out is None:
                out = np.empty((total,) + values.shape[1:])
            if k == 0:
                out[s:e] = values
                continue
            w = smoothstep(transition).reshape((-1,) + (1,) * (values.ndim - 1))
            prev = out[s : s + transition]
            out[s : s + transition] = blend(prev, values[:transition], w)
            out[s + transition : e] = values[transition:]
        return out

    pose = fill(lambda loc, p: loc.pose, blend=_blend_pose)
    step, turn = fill(lambda loc, p: loc.step), fill(lambda loc, p: loc.turn)
    rotations = root = None
    if rig:
        root = fill(lambda loc, p: loc.root)
        rotations = fill(_rig_rotations, blend=_slerp)  # the same weights, on the sphere
    # integrate the anchor: the first part's own start, then every (blended) step and turn
    first = _anchor(np.asarray(parts[0].joints[:1], dtype=np.float64))[0]
    yaw = heading(np.asarray(parts[0].joints, dtype=np.float64))[0] + np.concatenate([[0.0], np.cumsum(turn[:-1])])
    rot = yaw_matrix(yaw)
    moves = np.einsum("nab,nb->na", rot[:-1], np.stack([step[:-1, 0], np.zeros(total - 1), step[:-1, 1]], -1))
    ground = np.concatenate([[first], first + np.cumsum(moves, axis=0)])
    joints = np.einsum("nab,njb->nja", rot, pose) + ground[:, None]
    if rig:
        rotations[:, 0] = qmul(yaw_quat(yaw), rotations[:, 0])
        root = np.einsum("nab,nb->na", rot, root) + ground
    return Joined(joints, rotations, root, frames)


def _rig_rotations(loc: _Local, part: Part) -> np.ndarray:
    """The rig's local rotations with the root's in the heading frame."""
    return np.concatenate([loc.root_rot[:, None], part.rotations[:, 1:]], axis=1)


def _anchor(joints: np.ndarray) -> np.ndarray:
    """(N, 3) the mean of the four foot joints, on the ground (y = 0)."""
    feet = list(SMPL22.foot_joints[0]) + list(SMPL22.foot_joints[1])
    return joints[:, feet].mean(axis=1) * np.array([1.0, 0.0, 1.0])


def _lerp(a: np.ndarray, b: np.ndarray, w: np.ndarray) -> np.ndarray:
    return (1.0 - w) * a + w * b


def _blend_pose(a: np.ndarray, b: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Cross-fade two (T, 22, 3) anchor-relative poses bone by bone: each bone's direction is slerped and its length
    lerped, then the skeleton is rebuilt from the pelvis. Lerping positions instead lets a limb pass through its
    parent joint (a raised hand meeting a lowered one), and the bone's direction then flips: a 10 m/s wrist."""
    parents = np.array(SMPL22.parents)
    bone_a, bone_b = a[:, 1:] - a[:, parents[1:]], b[:, 1:] - b[:, parents[1:]]
    len_a, len_b = np.linalg.norm(bone_a, axis=-1), np.linalg.norm(bone_b, axis=-1)
    dir_a, dir_b = bone_a / np.maximum(len_a, 1e-9)[..., None], bone_b / np.maximum(len_b, 1e-9)[..., None]
    t = np.broadcast_to(w[..., 0], len_a.shape)
    theta = np.arccos(np.clip((dir_a * dir_b).sum(-1), -1.0, 1.0))
    sin = np.sin(theta)
    near = sin < 1e-6  # (anti)parallel: lerp (nearly opposite bones do not occur between two standing poses)
    safe = np.where(near, 1.0, sin)
    wa = np.where(near, 1.0 - t, np.sin((1.0 - t) * theta) / safe)[..., None]
    wb = np.where(near, t, np.sin(t * theta) / safe)[..., None]
    dirs = wa * dir_a + wb * dir_b
    bones = dirs / np.maximum(np.linalg.norm(dirs, axis=-1, keepdims=True), 1e-9) * _lerp(len_a, len_b, t)[..., None]
    out = np.empty_like(a)
    out[:, 0] = _lerp(a[:, 0], b[:, 0], w[..., 0])
    for j in range(1, a.shape[1]):  # parents come first in SMPL-22
        out[:, j] = out[:, parents[j]] + bones[:, j - 1]
    return out


def _slerp(a: np.ndarray, b: np.ndarray, w: np.ndarray) -> np.ndarray:
    return qslerp(a, b, np.broadcast_to(w[..., 0], a.shape[:-1]))


def place_canonically(joined: Joined, offsets: np.ndarray | None, rig: Skeleton | None) -> Joined:
    """HumanML3D's placement, as `prepare` gives every clip: SMPL-22 joints through `canonicalize_joints` (restores
    the bone lengths a cross-fade shortens; floor, origin, facing +Z), the native rig through `ground_and_face` with
    its own bones (floor, origin, facing +Z)."""
    joints = canonicalize_joints(joined.joints, SMPL22)
    if joined.rotations is None:
        return Joined(joints, None, None, joined.frames)
    translations = np.broadcast_to(offsets, joined.rotations.shape[:-1] + (3,)).copy()
    translations[:, 0] = joined.root
    world, _ = forward_kinematics(joined.rotations, translations, rig.parents)
    turn, shift = ground_and_face(world, rig)
    rotations = joined.rotations.copy()
    rotations[:, 0] = qmul(np.broadcast_to(turn, rotations[:, 0].shape), rotations[:, 0])
    root = qrot(np.broadcast_to(turn, joined.root.shape[:-1] + (4,)), joined.root + shift)
    return Joined(joints, rotations, root, joined.frames)


# ---- captions ----------------------------------------------------------------------------------------------------
_SUBJECT = re.compile(r"^(" + "|".join(re.escape(s) for s in SUBJECTS) + r")\s+", re.IGNORECASE)


def split_subject(caption: str) -> tuple[str, str]:
    """("a person", "walks forward") from "a person walks forward."; ("", caption) when no known subject opens it."""
    text = caption.strip().rstrip(".").strip()
    m = _SUBJECT.match(text)
    return (m.group(1), text[m.end() :]) if m else ("", text)


def join_captions(captions: list[str]) -> tuple[str, list[tuple[int, int]]]:
    """One sentence from per-clip captions: the first keeps its subject, the others are chained with ", then " and
    the last of three or more with ", and then ". Returns the text and each clip's [start, stop) character span."""
    text, spans = "", []
    for k, caption in enumerate(captions):
        subject, rest = split_subject(caption)
        if k == 0:
            piece = f"{subject} {rest}" if subject else rest
        else:
            text += ", and then " if k == len(captions) - 1 and len(captions) >= 3 else ", then "
            piece = rest
        spans.append((len(text), len(text) + len(piece)))
        text += piece
    return text + ".", spans
