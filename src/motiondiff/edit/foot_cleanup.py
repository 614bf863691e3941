"""Foot-skate cleanup (`cleanup=feet` in sample.py and edit.py): pin each foot where it stands and re-pose the legs.

Contacts, for each contact joint of `skeleton.foot_joints` (SMPL-22: ankle and toe of each foot), come from the
motion itself, read from its path smoothed over time (Gaussian, sigma CONTACT_SMOOTH_S = 0.05 s, so a planted foot
that jitters from frame to frame, as generated feet do, still counts as planted): a joint is in contact at a frame
when
- its height is within CONTACT_HEIGHT_M (5 cm) of its own low level in the motion (its 5th height percentile: an
  ankle stands higher above the floor than a toe, and a generated floor need not be at y = 0), and
- its horizontal speed (central difference) is below CONTACT_SPEED_M_S (0.5 m/s; a swinging foot is several times faster);
contact runs separated by at most GAP_S (0.1 s) are merged into one.

Each run pins its joint at one point, the run's mean position (the mean over the run's kept frames when it reaches
into them, so the generated frames continue the kept contact). Over BLEND_S (0.2 s) on each side of a run the
correction fades out (smoothstep). Per frame the foot (the ankle and everything below it) then moves rigidly: it is
translated so the heel (first contact joint) meets its target and turned by the shortest arc that points it at the
toe's (last contact joint) target; a joint not in contact follows the other's correction, so a foot rolling onto its
toe does not slide either. The knee is placed by analytic two-bone IK: hip fixed, the frame's thigh and shin lengths,
the knee in the plane of its original bend. Only knee, ankle and foot joints move and every bone keeps its length;
an ankle target beyond the straightened leg is pulled back into reach (the foot then misses its pin by that much).

`keep`: frames (N,) or joint positions (N, J) the user kept (an edit's in-between ends, body parts kept from the
input). A leg is not touched at a frame where any of its moved joints is kept, and corrections fade to zero over
BLEND_S towards kept frames. `foot_sliding` is the measure: mean horizontal speed (cm/s) of the contact joints
between consecutive contact frames.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter1d

from motiondiff.geometry.motion_checks import check_motion
from motiondiff.geometry.rotations import any_perpendicular, qbetween, qrot
from motiondiff.geometry.skeleton import Skeleton

CONTACT_HEIGHT_M = 0.05
CONTACT_SPEED_M_S = 0.5
CONTACT_SMOOTH_S = 0.05
LOW_PERCENTILE = 5.0
GAP_S = 0.1
BLEND_S = 0.2
MIN_FRAMES = 3
_REACH = 1.0 - 1e-6  # fraction of the straight leg an unreachable target is pulled back to


@dataclass
class FootCleanup:
    """A cleaned motion and what the cleanup did. Sliding: cm/s, on the contacts detected before the cleanup."""

    joints: np.ndarray  # (N, J, 3) cleaned
    contacts: np.ndarray  # (N, C) bool: contacts of the input, contact joints left foot then right foot
    sliding_before_cm_s: float
    sliding_after_cm_s: float
    frames_changed: int  # frames where some leg moved
    max_shift_m: float  # largest move of any joint
    unreachable_frames: int  # frames where an ankle target was out of the leg's reach

    def summary(self) -> dict:
        return {"sliding_before_cm_s": self.sliding_before_cm_s, "sliding_after_cm_s": self.sliding_after_cm_s,
                "contact_fraction": float(self.contacts.mean()) if self.contacts.size else 0.0,
                "frames_changed": self.frames_changed, "max_shift_m": self.max_shift_m,
                "unreachable_frames": self.unreachable_frames}  # fmt: skip


def contact_joints(skeleton: Skeleton) -> tuple[int, ...]:
    return tuple(skeleton.foot_joints[0]) + tuple(skeleton.foot_joints[1])


def detect_contacts(joints: np.ndarray, skeleton: Skeleton, fps: float) -> np.ndarray:
    """(N, C) bool contacts of the contact joints (left foot's, then right foot's) by the rule of the module doc."""
    joints = _check(joints, skeleton, fps)
    feet = list(contact_joints(skeleton))
    if len(joints) < MIN_FRAMES:
        return np.zeros((len(joints), len(feet)), dtype=bool)
    points = gaussian_filter1d(joints[:, feet], CONTACT_SMOOTH_S * fps, axis=0, mode="nearest")
    height = points[..., 1]
    speed = np.linalg.norm(np.gradient(points[..., [0, 2]], axis=0), axis=-1) * fps
    low = np.percentile(height, LOW_PERCENTILE, axis=0)
    contacts = (height < low + CONTACT_HEIGHT_M) & (speed < CONTACT_SPEED_M_S)
    gap = int(round(GAP_S * fps))
    for c in range(contacts.shape[1]):
        runs = _runs(contacts[:, c])
        for (_, end), (start, _) in zip(runs[:-1], runs[1:], strict=True):
            if start - end - 1 <= gap:
                contacts[end:start, c] = True
    return contacts


def foot_sliding(joints: np.ndarray, skeleton: Skeleton, fps: float, contacts: np.ndarray | None = None) -> float:
    """Mean horizontal speed (cm/s) of the contact joints over consecutive frame pairs both in contact (`contacts`
    default: detected on these joints); 0 without contacts."""
    joints = _check(joints, skeleton, fps)
    contacts = detect_contacts(joints, skeleton, fps) if contacts is None else np.asarray(contacts, dtype=bool)
    points = joints[:, list(contact_joints(skeleton))][..., [0, 2]]
    speed = np.linalg.norm(np.diff(points, axis=0), axis=-1) * fps
    both = contacts[1:] & contacts[:-1]
    return float(100.0 * speed[both].mean()) if both.any() else 0.0


def clean_foot_skate(joints: np.ndarray, skeleton: Skeleton, fps: float, keep: np.ndarray | None = None) -> FootCleanup:
    """The motion (N, J, 3) with its feet pinned during contacts and its legs re-posed (module doc); `keep` frames
    (N,) or points (N, J) are returned exactly as given."""
    joints = _check(joints, skeleton, fps)
    kept = _kept_points(keep, joints.shape[:2])
    contacts = detect_contacts(joints, skeleton, fps)
    out = joints.copy()
    unreachable = 0
    feet = contact_joints(skeleton)
    for foot in skeleton.foot_joints:
        hip, knee, ankle = _leg(joints, skeleton, foot[0])
        segment = [ankle, *_descendants(skeleton, ankle)]
        leg_kept = kept[:, [knee, *segment]].any(axis=1)
        pair = (foot[0], foot[-1])  # heel and toe
        fixes = [_pins(joints[:, j], contacts[:, feet.index(j)], leg_kept, fps) for j in pair]
        unreachable += _repose_leg(out, joints, (hip, knee, ankle), segment, pair, *fixes, leg_kept)
    out[kept] = joints[kept]
    shift = np.linalg.norm(out - joints, axis=-1)
    return FootCleanup(
        joints=out, contacts=contacts, sliding_before_cm_s=foot_sliding(joints, skeleton, fps, contacts),
        sliding_after_cm_s=foot_sliding(out, skeleton, fps, contacts),
        frames_changed=int((shift > 0).any(axis=1).sum()), max_shift_m=float(shift.max(initial=0.0)),
        unreachable_frames=unreachable,
    )  # fmt: skip


# ---- pins and blends ----------------------------------------------------------------------------------------------
def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Inclusive (start, end) of each run of True."""
    padded = np.concatenate([[False], mask, [False]]).astype(np.int8)
    edges = np.flatnonzero(np.diff(padded))
    return [(int(s), int(e) - 1) for s, e in zip(edges[::2], edges[1::2], strict=True)]


def _smoothstep(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


def _pins(points: np.ndarray, contact: np.ndarray, kept: np.ndarray, fps: float) -> np.ndarray:
    """(N, 3) correction of one contact joint: pin - position in its contact runs, the boundary's correction fading
    out over BLEND_S around them, everything faded to zero towards kept frames."""
    n = len(points)
    blend = max(1, int(round(BLEND_S * fps)))
    weight, delta = np.zeros(n), np.zeros((n, 3))
    for start, end in _runs(contact):
        run = slice(start, end + 1)
        inside_kept = kept[run]
        pin = points[run][inside_kept].mean(axis=0) if inside_kept.any() else points[run].mean(axis=0)
        weight[run], delta[run] = 1.0, pin - points[run]
        for edge, step in ((start, -1), (end, 1)):
            for k in range(1, blend + 1):
                t = edge + step * k
                w = float(_smoothstep(1.0 - k / (blend + 1)))
                if not 0 <= t < n or w <= weight[t]:
                    continue
                weight[t], delta[t] = w, delta[edge]
    if kept.any():  # frames from the nearest kept frame, for the fade towards it
        index = np.arange(n)
        kept_at = np.flatnonzero(kept)
        distance = np.abs(index[:, None] - kept_at[None]).min(axis=1)
        weight = weight * _smoothstep(distance / blend)
    return weight[:, None] * delta


# ---- legs ---------------------------------------------------------------------------------------------------------
def _leg(joints: np.ndarray, skeleton: Skeleton, heel: int) -> tuple[int, int, int]:
    """(hip, knee, ankle) above a foot's first contact joint: the ankle is the first joint from the heel upwards
    whose own bone (shin) and parent's bone (thigh) are both at least half the longest bone on the way to the root
    (SMPL-22's ankle is its heel contact joint; KIT-21's sits one joint above its)."""
    parents = skeleton.parents
    path = [heel]
    while parents[path[-1]] >= 0:
        path.append(parents[path[-1]])
    if len(path) < 4:
        raise ValueError(f"foot cleanup: joint {skeleton.joint_names[heel]!r} of {skeleton.name!r} has no hip-knee-"
                         "ankle chain above it")  # fmt: skip
    length = {j: float(np.median(np.linalg.norm(joints[:, j] - joints[:, parents[j]], axis=-1))) for j in path[:-1]}
    longest = max(length.values())
    for ankle in path[:-3]:
        knee = parents[ankle]
        if length[ankle] >= 0.5 * longest and length[knee] >= 0.5 * longest:
            return parents[knee], knee, ankle
    return path[2], path[1], path[0]


def _descendants(skeleton: Skeleton, joint: int) -> list[int]:
    out, todo = [], list(skeleton.children[joint])
    while todo:
        j = todo.pop()
        out.append(j)
        todo.extend(skeleton.children[j])
    return sorted(out)


def _repose_leg(out, joints, chain, segment, contact_pair, heel_fix, toe_fix, leg_kept) -> int:
    """Move one leg in `out` at the frames its corrections touch; returns the frames whose ankle was out of reach."""
    hip, knee, ankle = chain
    heel, toe = contact_pair
    heel_w = np.linalg.norm(heel_fix, axis=-1) > 0
    toe_w = np.linalg.norm(toe_fix, axis=-1) > 0
    frames = np.flatnonzero((heel_w | toe_w) & ~leg_kept)
    if len(frames) == 0:
        return 0
    p = joints[frames]
    # each contact joint's target; one without its own correction follows the other's
    heel_target = p[:, heel] + np.where(heel_w[frames, None], heel_fix[frames], toe_fix[frames])
    toe_target = p[:, toe] + np.where(toe_w[frames, None], toe_fix[frames], heel_fix[frames])
    turn = np.tile([1.0, 0.0, 0.0, 0.0], (len(frames), 1))
    if toe != heel:
        turn = qbetween(p[:, toe] - p[:, heel], toe_target - heel_target)
    foot = heel_target[:, None] + qrot(turn[:, None], p[:, segment] - p[:, [heel]])  # rigid foot, (F, S, 3)
    target = foot[:, 0]  # the ankle is the segment's first joint
    top, thigh = p[:, hip], np.linalg.norm(p[:, knee] - p[:, hip], axis=-1)
    shin = np.linalg.norm(p[:, ankle] - p[:, knee], axis=-1)
    reach = target - top
    distance = np.linalg.norm(reach, axis=-1)
    direction = reach / np.maximum(distance, 1e-12)[:, None]
    clamped = np.clip(distance, np.abs(thigh - shin) / _REACH, (thigh + shin) * _REACH)
    unreachable = int((clamped < distance).sum())
    foot += ((clamped - distance)[:, None] * direction)[:, None]  # pulled back (or out) along the hip-ankle line
    # knee: in the plane of the original knee and the new hip-ankle line
    bend = p[:, knee] - top
    pole = bend - (bend * direction).sum(-1, keepdims=True) * direction
    size = np.linalg.norm(pole, axis=-1, keepdims=True)
    pole = np.where(size > 1e-9, pole / np.maximum(size, 1e-12), any_perpendicular(direction))
    cos = np.clip((thigh**2 + clamped**2 - shin**2) / np.maximum(2.0 * thigh * clamped, 1e-12), -1.0, 1.0)
    sin = np.sqrt(1.0 - cos**2)
    rows = out[frames]
    rows[:, knee] = top + thigh[:, None] * (cos[:, None] * direction + sin[:, None] * pole)
    rows[:, segment] = foot
    out[frames] = rows
    return unreachable


def _check(joints: np.ndarray, skeleton: Skeleton, fps: float) -> np.ndarray:
    joints = check_motion(joints, skeleton, fps, "foot cleanup")
    if not all(skeleton.foot_joints):
        raise ValueError(f"foot cleanup: skeleton {skeleton.name!r} names no foot joints on one side")
    return joints


def _kept_points(keep, shape: tuple[int, int]) -> np.ndarray:
    if keep is None:
        return np.zeros(shape, dtype=bool)
    keep = np.asarray(keep, dtype=bool)
    if keep.shape == shape[:1]:
        return np.repeat(keep[:, None], shape[1], axis=1)
    if keep.shape != shape:
        raise ValueError(
            f"foot cleanup: keep must be kept frames ({shape[0]},) or kept points {shape}, got {keep.shape}"
        )
    return keep
