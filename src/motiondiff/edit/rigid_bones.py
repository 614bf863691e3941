"""Rigid bones (`cleanup=bones`): the motion on one fixed skeleton, as closely as a fixed skeleton can follow it.

Generated joints change their bone lengths from frame to frame (the released text model: a wrist or shin bone by up
to 13 cm over a motion), which no rig can show: a BVH, FBX or SMPL file has one set of bone lengths, so each export
fits the motion on its own and the files disagree with the saved joints by the fit error. This cleanup does the fit
once, on the joints themselves: rest offsets from the motion (`inverse_kinematics.fit_rest_offsets`: median bone
lengths, the data's pelvis and chest arrangement), rotations by IK, then rotations and lengths polished to keep the
worst joint close (`refine_rotations`); the cleaned joints are forward kinematics of that fit, so every later export
reproduces them exactly. The root keeps its path.

No fixed skeleton can do better than a quarter of a bone's length range over the motion at that bone's ends (the two
ends' errors must add up to the length change, in both directions), which the report gives as `bound_m`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from motiondiff.geometry.inverse_kinematics import fit_rest_offsets, fit_rotations
from motiondiff.geometry.kinematics import forward_kinematics
from motiondiff.geometry.motion_checks import check_motion
from motiondiff.geometry.skeleton import Skeleton

TWIST_HALF_LIFE_S = 1.0  # as the exports' IK
FIT_ABOVE_M = 1e-4  # IK error above which the polish runs (a real, rigid clip is reproduced to float precision)


@dataclass
class RigidBones:
    """A motion on one fixed skeleton and what that cost. Moves in metres, lengths per bone (J - 1)."""

    joints: np.ndarray  # (N, J, 3) forward kinematics of the fit
    offsets: np.ndarray  # (J, 3) the skeleton's rest offsets (row 0 zero)
    max_move_m: float  # largest distance of any joint from where the motion had it
    mean_move_m: float
    bound_m: float  # no fixed skeleton moves the worst joint less than this (module doc)
    length_range_before_m: float  # largest change of one bone's length over the motion

    def summary(self) -> dict:
        return {"max_move_m": self.max_move_m, "mean_move_m": self.mean_move_m, "bound_m": self.bound_m,
                "bone_length_range_before_m": self.length_range_before_m}  # fmt: skip


def bone_length_range(joints: np.ndarray, skeleton: Skeleton) -> np.ndarray:
    """Per bone (J - 1,): its longest minus its shortest length over the frames of joints (N, J, 3)."""
    parents = np.asarray(skeleton.parents)
    lengths = np.linalg.norm(joints[:, 1:] - joints[:, parents[1:]], axis=-1)
    return lengths.max(axis=0) - lengths.min(axis=0)


def rigid_bones(joints: np.ndarray, skeleton: Skeleton, fps: float) -> RigidBones:
    """Joints (N, J, 3) refitted on one fixed skeleton (module doc)."""
    joints = check_motion(joints, skeleton, fps, "bone cleanup")
    offsets = fit_rest_offsets(joints, skeleton)
    rotations, root, offsets = fit_rotations(joints, skeleton, offsets, twist_half_life=TWIST_HALF_LIFE_S * fps,
                                             refine_above=FIT_ABOVE_M)  # fmt: skip
    fitted = _fk(rotations, root, offsets, skeleton)
    move = np.linalg.norm(fitted - joints, axis=-1)
    spread = bone_length_range(joints, skeleton)
    return RigidBones(joints=fitted, offsets=offsets, max_move_m=float(move.max()), mean_move_m=float(move.mean()),
                      bound_m=float(spread.max(initial=0.0)) / 4, length_range_before_m=float(spread.max(initial=0.0)))  # fmt: skip


def _fk(rotations: np.ndarray, root: np.ndarray, offsets: np.ndarray, skeleton: Skeleton) -> np.ndarray:
    translations = np.repeat(offsets[None], len(rotations), axis=0)
    translations[:, 0] = root
    return forward_kinematics(rotations, translations, skeleton.parents)[0]
