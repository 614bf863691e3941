"""The pose keywords the exports share (`rotations`, `root`, `offsets` of export_bvh and export_smpl), declared and
checked once, so that both exports accept the same inputs and refuse bad ones with the same messages."""

from __future__ import annotations

from collections.abc import Mapping
from typing import NamedTuple

import numpy as np

from motiondiff.geometry.rotations import qfix, qnormalize
from motiondiff.geometry.skeleton import Skeleton


class PoseInputs(NamedTuple):
    """`rotations` (N, J, 4) local quaternions (w, x, y, z; the root's global) and `root` (N, 3) positions, as a
    rotation representation gives them (both or neither: without them the export solves rotations by IK), and rest
    `offsets` (J, 3) of each joint from its parent (metres; with rotations, the skeleton's when not given)."""

    rotations: np.ndarray | None = None
    root: np.ndarray | None = None
    offsets: np.ndarray | None = None

    @classmethod
    def checked(cls, caller: str, joints: np.ndarray, skeleton: Skeleton, pose: Mapping) -> PoseInputs:
        """The `pose` keywords given to `caller` for `joints` (N, J, 3) on `skeleton`, as float arrays (unit,
        sign-continuous rotations); TypeError for an unknown keyword, ValueError naming the fix for a bad value."""
        unknown = sorted(set(pose) - set(cls._fields))
        if unknown:
            raise TypeError(f"{caller}() got unexpected keyword argument(s) {', '.join(unknown)}; its pose keywords "
                            f"are {', '.join(cls._fields)}")  # fmt: skip
        rotations, root, offsets = cls(**pose)
        if (rotations is None) != (root is None):
            raise ValueError(
                f"{caller}: pass both rotations and root (a rotation representation's output) or neither (rotations "
                "are then solved from the joints)"
            )
        if rotations is not None:
            rotations, root = _rotations(caller, rotations, root, joints.shape[:2])
            offsets = skeleton.offsets if offsets is None else offsets
        return cls(rotations, root, None if offsets is None else _offsets(caller, offsets, skeleton.num_joints))


def _rotations(caller: str, rotations, root, shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    rotations, root = np.asarray(rotations, dtype=np.float64), np.asarray(root, dtype=np.float64)
    n, j = shape
    if rotations.shape != (n, j, 4) or root.shape != (n, 3):
        raise ValueError(
            f"{caller}: rotations must be ({n}, {j}, 4) local quaternions (w, x, y, z) and root ({n}, 3) to match "
            f"the joints, got {rotations.shape} and {root.shape}"
        )
    if not (np.isfinite(rotations).all() and np.isfinite(root).all()):
        raise ValueError(f"{caller}: rotations or root contain NaN or Inf; the motion diverged, resample it")
    if (np.linalg.norm(rotations, axis=-1) < 1e-6).any():
        raise ValueError(f"{caller}: some rotation quaternions are zero; pass unit quaternions (w, x, y, z)")
    return qfix(qnormalize(rotations)), root


def _offsets(caller: str, offsets, count: int) -> np.ndarray:
    offsets = np.asarray(offsets, dtype=np.float64)
    if offsets.shape != (count, 3) or not np.isfinite(offsets).all():
        raise ValueError(
            f"{caller}: offsets must be finite with shape ({count}, 3) (rest offset of each joint from its parent, "
            f"metres), got {offsets.shape}"
        )
    return offsets
