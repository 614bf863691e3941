"""Which way is up in a motion file, and the turn that makes it Y-up (the project's convention).

Animation tools differ: Blender and 3ds Max are Z-up, Maya, MotionBuilder and most BVH files Y-up, and a Blender
export may keep Blender's Z. A motion read with the wrong up axis lies on the ground, and nothing downstream notices
(the editing of a lying body keeps its part exactly as well as a standing one), so every motion file is checked.

The rule (`detect_up_axis`): up is the signed axis along which the HEAD sits above the FEET.

- Motion: for every frame the direction from the mean of the feet to the head, made unit length (frames where the
  head and feet nearly coincide, closer than a quarter of the clip's median distance, are left out), is averaged
  over the frames. The largest component of that mean, with its sign, is the motion's up axis when it is at least
  MIN_MOTION_SHARE (0.5: the body leans less than 60 degrees from it on average) and at least SEPARATION (2) times
  every other component. Standing, walking, bowing and jumping all pass; a body that tumbles, or stands for half the
  clip and lies for the other half, does not.
- Rest pose (BVH files): the same direction in the hierarchy's rest pose (all rotations zero). It counts only when
  the rest pose is a standing body: head-to-feet at least REST_STANDING (0.8) of the motion's median distance and
  along one axis within about 25 degrees (component >= REST_ALIGNED, 0.9). Rigs whose rest pose is not a standing
  body (the Bandai files lay their bones along x with a 0.5 m head-to-feet) give no rest evidence.
- Decision: the motion's axis when the rest pose agrees or says nothing; the rest pose's axis when the motion says
  nothing. Otherwise the file cannot be decided, because the motion gives no axis (the body tumbles, lies for as
  long as it stands, or head and feet coincide) and there is no standing rest pose, or because the motion and a
  standing rest pose disagree (e.g. a Y-up file whose body lies on the floor all along, head and feet at the same
  height, which the motion alone would read as a body standing along the floor axis; or a root rotation that turns
  a Y-up rest pose): then an `UpAxisWarning` names the file and the `up_axis=` override, and the file is read as
  Y-up.

`up_axis` values: "auto" (the rule above), or a forced axis "y", "z", "x" (= "+y", ...), "-y", "-z", "-x": the
direction the head points in the file. `rotation_to_y_up(axis)` is the proper rotation that turns it to +Y
(+Z -> +Y turns -Y to +Z, which is Blender's own export convention, so a Blender Z-up character facing -Y faces +Z).

Limit: a joints file (.npy/.npz: no rest pose), or a BVH whose rest pose is not a standing body, in which the body
lies along one axis all along (push-ups, crawling) looks exactly like a body standing along that axis; such files
need `up_axis=y`.
"""

from __future__ import annotations

import warnings
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING

import numpy as np

from motiondiff.geometry.kinematics import forward_kinematics
from motiondiff.geometry.skeleton import SMPL22

if TYPE_CHECKING:
    from motiondiff.data.formats.bvh import BVHMotion
    from motiondiff.data.formats.joint_map import JointMap

__all__ = [
    "AXES",
    "UpAxis",
    "UpAxisWarning",
    "bvh_up_axis",
    "detect_up_axis",
    "parse_up_axis",
    "rotation_to_y_up",
    "undecided",
]

AXES = ("+y", "-y", "+z", "-z", "+x", "-x")
MIN_MOTION_SHARE = 0.5
SEPARATION = 2.0
REST_STANDING = 0.8
REST_ALIGNED = 0.9
MAX_FRAMES = 2000  # frames of a BVH looked at (evenly spread over longer files)
_NEAR = 0.25  # frames whose head-to-feet distance is below this fraction of the median carry no direction

_TO_Y_UP = {  # rows: new x, y, z in terms of the file's axes (proper rotations, det +1)
    "+y": ((1, 0, 0), (0, 1, 0), (0, 0, 1)),
    "-y": ((1, 0, 0), (0, -1, 0), (0, 0, -1)),
    "+z": ((1, 0, 0), (0, 0, 1), (0, -1, 0)),
    "-z": ((1, 0, 0), (0, 0, -1), (0, 1, 0)),
    "+x": ((0, -1, 0), (1, 0, 0), (0, 0, 1)),
    "-x": ((0, 1, 0), (-1, 0, 0), (0, 0, 1)),
}
FORCE_HINT = "force it with up_axis=y|z|x (or -y, -z, -x: the direction the head points in the file)"


class UpAxisWarning(UserWarning):
    """A motion file whose up axis cannot be decided; it is read as Y-up."""


@dataclass(frozen=True)
class UpAxis:
    """The up axis of a motion and how it was found.

    axis: "+y", "-z", ... (the file's direction the head points in); decided: False when the rule could not tell
    (the motion was then read as Y-up); how: "forced", "motion", "motion and rest pose", "rest pose" or "undecided";
    motion_axis / rest_axis: what each piece of evidence said (None: nothing); share: the motion's mean head-over-feet
    component along its axis (1 = straight up in every frame); reason: why it is undecided ('' otherwise)."""

    axis: str
    decided: bool
    how: str
    motion_axis: str | None = None
    rest_axis: str | None = None
    share: float = 0.0
    reason: str = ""

    @property
    def matrix(self) -> np.ndarray:
        return rotation_to_y_up(self.axis)

    def describe(self) -> str:
        if self.how == "forced":
            return f"{self.axis} (forced)"
        if not self.decided:
            return f"undecided ({self.reason}); read as {self.axis}"
        return f"{self.axis} (from the {self.how}; head over feet {self.share:.2f})"

    def to_json(self) -> dict:
        return asdict(self)


def parse_up_axis(value) -> str | None:
    """'auto' -> None; 'y'/'+y' -> '+y', '-z' -> '-z', ... ValueError naming the choices otherwise."""
    text = str(value).strip().lower()
    if text == "auto":
        return None
    text = "+" + text if text in ("x", "y", "z") else text
    if text not in AXES:
        raise ValueError(
            f"up_axis={value!r} is not an axis; choose auto (detect it), y, z, x, or a signed axis "
            f"({', '.join(AXES)}): the direction the head points in the file"
        )
    return text


def rotation_to_y_up(axis: str) -> np.ndarray:
    """(3, 3) rotation R (new = R @ old) that turns the signed `axis` to +Y."""
    return np.array(_TO_Y_UP[parse_up_axis(axis) or "+y"], dtype=np.float64)


def _signed(k: int, value: float) -> str:
    return ("+" if value >= 0 else "-") + "xyz"[k]


def _motion_vote(positions: np.ndarray, head: int, feet) -> tuple[str | None, float, float, str]:
    """(axis or None, share, median head-to-feet distance, why not) from the frames."""
    if len(positions) == 0:
        return None, 0.0, 0.0, "it has no frames"
    d = positions[:, head] - positions[:, list(feet)].mean(axis=1)
    length = np.linalg.norm(d, axis=-1)
    finite = np.isfinite(length)
    scale = float(np.median(length[finite])) if finite.any() else 0.0
    if not scale > 0:
        return None, 0.0, 0.0, "the head and the feet are at the same place in every frame"
    use = finite & (length > _NEAR * scale)
    mean = (d[use] / length[use, None]).mean(axis=0)
    order = np.argsort(-np.abs(mean))
    k, share, second = int(order[0]), float(abs(mean[order[0]])), float(abs(mean[order[1]]))
    if share < MIN_MOTION_SHARE:
        return (
            None,
            share,
            scale,
            (
                f"no axis has the head above the feet on average (largest mean component {share:.2f} < "
                f"{MIN_MOTION_SHARE})"
            ),
        )
    if second * SEPARATION > share:
        return (
            None,
            share,
            scale,
            (
                f"the head is above the feet along two axes ({_signed(k, mean[k])} {share:.2f}, "
                f"{_signed(int(order[1]), mean[order[1]])} {second:.2f})"
            ),
        )
    return _signed(k, mean[k]), share, scale, ""


def _rest_vote(rest: np.ndarray | None, head: int, feet, scale: float) -> str | None:
    if rest is None:
        return None
    d = rest[head] - rest[list(feet)].mean(axis=0)
    length = float(np.linalg.norm(d))
    if not (length > 0 and np.isfinite(length)) or (scale > 0 and length < REST_STANDING * scale):
        return None
    k = int(np.argmax(np.abs(d)))
    return _signed(k, d[k]) if abs(d[k]) >= REST_ALIGNED * length else None


def detect_up_axis(
    positions: np.ndarray,
    head: int,
    feet,
    *,
    rest: np.ndarray | None = None,
    up_axis: str = "auto",
    source: str = "<motion>",
    warn: bool = True,
) -> UpAxis:
    """The up axis of joint `positions` (F, J, 3) (any units) by the rule of this module; `head` and `feet` index
    the joints, `rest` (J, 3) is the rest pose where there is one (BVH). A forced `up_axis` is returned as it is. An
    undecidable motion warns (`UpAxisWarning`, naming `source` and the override) unless `warn` is False, and is
    read as +y."""
    forced = parse_up_axis(up_axis)
    if forced is not None:
        return UpAxis(forced, True, "forced")
    positions = np.asarray(positions, dtype=np.float64)
    if positions.ndim != 3 or positions.shape[-1] != 3:
        raise ValueError(f"detect_up_axis: positions must be (frames, joints, 3), got {positions.shape}")
    motion, share, scale, why = _motion_vote(positions, head, feet)
    rest_axis = _rest_vote(None if rest is None else np.asarray(rest, dtype=np.float64), head, feet, scale)
    if motion is not None and rest_axis in (None, motion):
        how = "motion" if rest_axis is None else "motion and rest pose"
        return UpAxis(motion, True, how, motion, rest_axis, share)
    if motion is None and rest_axis is not None:
        return UpAxis(rest_axis, True, "rest pose", None, rest_axis, share)
    if motion is None:
        reason = why + ("" if rest is None else ", and the rest pose is not a standing body")
    else:
        reason = (
            f"the motion has the head above the feet along {motion} but the rest pose stands along {rest_axis} "
            "(a body lying down all along, or a root rotation that turns the rest pose)"
        )
    return undecided(source, reason, motion, rest_axis, share, warn=warn)


def undecided(source: str, reason: str, motion_axis=None, rest_axis=None, share=0.0, *, warn: bool = True) -> UpAxis:
    """The Y-up reading of a motion whose up axis cannot be decided, with an `UpAxisWarning` that names `source`,
    the `reason` and the `up_axis=` override."""
    if warn:
        warnings.warn(f"{source}: cannot tell the up axis: {reason}; reading it as Y-up. If the body lies down, "
                      f"{FORCE_HINT}", UpAxisWarning, stacklevel=3)  # fmt: skip
    return UpAxis("+y", False, "undecided", motion_axis, rest_axis, float(share), reason)


def bvh_up_axis(
    motion: BVHMotion, joint_map: JointMap, *, up_axis: str = "auto", warn: bool = True, rest_pose: bool = True
) -> UpAxis:
    """`detect_up_axis` on a BVH's SMPL-22 joints (through `joint_map`): head = SMPL's head, feet = ankles and toes;
    the rest pose is the hierarchy with every rotation zero (OFFSETs only). `rest_pose=False`: the rest pose is no
    evidence (SMPL parameter files stand in SMPL's Y-up template whatever their data's up axis)."""

    if parse_up_axis(up_axis) is not None:
        return detect_up_axis(np.zeros((1, 1, 3)), 0, [0], up_axis=up_axis)
    head, feet = SMPL22.index("head"), [j for side in SMPL22.foot_joints for j in side]
    identity = np.zeros((1, motion.num_joints, 4))
    identity[..., 0] = 1.0
    rest = forward_kinematics(identity, motion.offsets[None], motion.parents)[0][0]
    step = -(-motion.num_frames // MAX_FRAMES)  # long captures: every step-th frame is evidence enough
    every = slice(None, None, max(step, 1))
    world = forward_kinematics(motion.rotations[every], motion.translations[every], motion.parents)[0]
    mapped = joint_map.apply(world, motion.joint_names, to_metres=False)
    rest_mapped = joint_map.apply(rest, motion.joint_names, to_metres=False)
    return detect_up_axis(mapped, head, feet, rest=rest_mapped if rest_pose else None, source=motion.source, warn=warn)
