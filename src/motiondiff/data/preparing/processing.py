"""One BVH clip -> the arrays a prepared dataset stores (canonical SMPL-22 joints + native rotations)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from motiondiff.data.formats.bvh import BVHMotion
from motiondiff.data.formats.bvh_parse import MAX_FRAME_JOINTS
from motiondiff.data.formats.joint_map import JointMap
from motiondiff.data.preparing.captions import MotionFacts, measure
from motiondiff.data.representations.hml_features import canonicalize_joints, ground_and_face
from motiondiff.geometry.kinematics import forward_kinematics
from motiondiff.geometry.rotations import qmul, qrot
from motiondiff.geometry.skeleton import SMPL22, Skeleton

TARGET_FPS = 20.0
MIN_FRAMES = 2  # features need two frames; datasets apply their own, larger minimum when loading
BONE_TOLERANCE = 1e-3  # metres; non-root joints must keep a constant offset (rigid bones)
MAX_RESAMPLED_FRAMES = 200_000  # frames at TARGET_FPS a clip may become (2.8 hours)


class ClipError(ValueError):
    """A clip that cannot be used; the message is the reason shown in the prepare report."""


@dataclass
class NativeSkeleton:
    joint_names: list[str]
    parents: np.ndarray
    offsets: np.ndarray  # (J, 3) metres

    def skeleton(self, name: str) -> Skeleton:
        return Skeleton.infer(name, self.joint_names, self.parents, self.offsets, fps=TARGET_FPS)

    def same_topology(self, other: NativeSkeleton) -> bool:
        """Same joints and hierarchy; bone lengths may differ (performers and capture sessions differ)."""
        return self.joint_names == other.joint_names and np.array_equal(self.parents, other.parents)


@dataclass
class ProcessedClip:
    joints: np.ndarray  # (N, 22, 3) float32 canonical SMPL-22 joints (HumanML3D's new_joints)
    native_rotations: np.ndarray  # (N, J, 4) float32 local quaternions, canonical placement
    native_root: np.ndarray  # (N, 3) float32
    native: NativeSkeleton
    facts: MotionFacts
    up_axis: str = "+y"  # the file's up axis, turned to +y


def _collapse_placeholder_root(motion: BVHMotion) -> tuple[list[str], np.ndarray, np.ndarray, np.ndarray]:
    """Many exports (Bandai's `joint_Root`, a point on the ground) put a root above the real body root and move
    the body root with its own position channels. The rotation representations want the moving body joint as the
    root with rigid bones below it, so a root with a single child whose translation varies (or that never moves
    itself) is folded into that child: the child's world rotation and position become the new root's."""
    names, parents = list(motion.joint_names), motion.parents.copy()
    rot, trans = motion.rotations, motion.translations
    single_child = (parents == 0).sum() == 1 and len(parents) > 1 and parents[1] == 0
    child_moves = np.abs(trans[:, 1] - trans[:1, 1]).max() > 1e-9
    root_static = np.abs(trans[:, 0]).max() < 1e-9 and np.abs(np.abs(rot[:, 0, 0]) - 1).max() < 1e-9
    if not (single_child and (child_moves or root_static)):
        return names, parents, rot, trans
    rot, trans = rot[:, 1:].copy(), trans[:, 1:].copy()
    rot[:, 0] = qmul(motion.rotations[:, 0], motion.rotations[:, 1])
    trans[:, 0] = motion.translations[:, 0] + qrot(motion.rotations[:, 0], motion.translations[:, 1])
    return names[1:], np.where(parents[1:] > 0, parents[1:] - 1, -1), rot, trans


def native_motion(motion: BVHMotion) -> tuple[NativeSkeleton, np.ndarray, np.ndarray]:
    """Skeleton with constant offsets, local rotations (N, J, 4) and root positions (N, 3)."""
    names, parents, rot, trans = _collapse_placeholder_root(motion)
    offsets = trans[0].copy()
    drift = np.abs(trans[:, 1:] - offsets[None, 1:]).max(axis=(0, 2))
    if drift.max() > BONE_TOLERANCE:
        j = int(drift.argmax()) + 1
        raise ClipError(
            f"joint {names[j]} moves relative to its parent by up to {drift.max():.4f} m: only rigid bones "
            "(position channels on the root) are supported"
        )
    offsets[0] = 0.0
    return NativeSkeleton(names, parents, offsets), rot, trans[:, 0]


def process_motion(
    motion: BVHMotion,
    joint_map: JointMap,
    window: tuple[int, int] | None = None,
    skeleton_name: str = "native",
    turn: np.ndarray | None = None,
) -> ProcessedClip:
    """Resample to 20 fps (only the `window` (start, stop) frames at 20 fps if given), turn the axes by `turn` (3, 3)
    if given (`BVHMotion.rotated`, e.g. Z-up to Y-up), convert to metres, map to SMPL-22 and canonicalise (floor,
    origin, facing +Z) both the 22 joints (with HumanML3D's uniform skeleton) and the native skeleton (same
    placement rule, its own bones)."""
    if motion.num_frames < 1:
        raise ClipError("the file has no frames")
    total = motion.resampled_frames(TARGET_FPS)
    kept = total if window is None else max(min(window[1], total) - window[0], 0)
    if total > MAX_RESAMPLED_FRAMES or kept * motion.num_joints > MAX_FRAME_JOINTS:
        raise ClipError(f"{motion.num_frames} frames at {motion.fps:g} fps make {total} frames at {TARGET_FPS:g} fps "
                        f"of {motion.num_joints} joints, more than {MAX_RESAMPLED_FRAMES} frames or "
                        f"{MAX_FRAME_JOINTS} frames x joints; split the capture into shorter files")  # fmt: skip
    m = motion.resample(TARGET_FPS, window)
    m = (m if turn is None else m.rotated(turn)).scaled(joint_map.units_to_metres)
    if m.num_frames < MIN_FRAMES:
        raise ClipError(f"only {m.num_frames} frame(s) at {TARGET_FPS:g} fps; at least {MIN_FRAMES} are needed")
    world = m.positions()
    if not np.isfinite(world).all():
        raise ClipError("joint positions are not finite (NaN/Inf in the file)")
    joints = canonicalize_joints(joint_map.apply(world, m.joint_names, to_metres=False), SMPL22).astype(np.float32)

    native, rot, root = native_motion(m)
    translations = np.broadcast_to(native.offsets, rot.shape[:-1] + (3,)).copy()
    translations[:, 0] = root
    native_world, _ = forward_kinematics(rot, translations, native.parents)
    turn, shift = ground_and_face(native_world, native.skeleton(skeleton_name))
    rot = rot.copy()
    rot[:, 0] = qmul(np.broadcast_to(turn, rot[:, 0].shape), rot[:, 0])
    root = qrot(np.broadcast_to(turn, root.shape[:-1] + (4,)), root + shift)
    return ProcessedClip(
        joints=joints,
        native_rotations=rot.astype(np.float32),
        native_root=root.astype(np.float32),
        native=native,
        facts=measure(joints, TARGET_FPS),
    )


def most_active_window(joints: np.ndarray, frames: int) -> tuple[int, int]:
    """The `frames`-long window with the most joint movement (keeps the bow of a clip that starts standing)."""
    if len(joints) <= frames:
        return 0, len(joints)
    speed = np.linalg.norm(np.diff(joints, axis=0), axis=-1).sum(-1)
    totals = np.convolve(speed, np.ones(frames - 1), mode="valid")
    start = int(totals.argmax())
    return start, start + frames
