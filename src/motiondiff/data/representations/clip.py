"""`ClipMotion`: one clip as every dataset loader hands it to the representations.

A representation (motiondiff.data.representations) encodes features from these arrays, so a dataset only has to
say what it has: canonical joints of its feature skeleton (what HumanML3D-style features and the evaluators read)
and, where the source has them, local joint rotations on its own rig (what the vvMDM rotation representations read).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from motiondiff.geometry.kinematics import forward_kinematics
from motiondiff.geometry.skeleton import Skeleton


@dataclass
class ClipMotion:
    """One clip at the dataset's frame rate, metres, y up, canonical placement (floor y=0, facing +Z at frame 0).

    joints     (N, Jf, 3)  joints of the dataset's feature skeleton (SMPL-22 or KIT-21): HumanML3D's new_joints
    rotations  (N, J, 4)   local joint quaternions (w, x, y, z) on `rig`; None when the source has no rotations
    root       (N, 3)      world position of the rig's root joint; None with `rotations`
    offsets    (J, 3)      this clip's bone offsets (performers differ); None means `rig.offsets`
    rig        Skeleton    the rotation skeleton (names, parents, mean offsets); None with `rotations`
    """

    joints: np.ndarray
    rotations: np.ndarray | None = None
    root: np.ndarray | None = None
    offsets: np.ndarray | None = None
    rig: Skeleton | None = None

    def __post_init__(self):
        n = len(self.joints)
        if self.rotations is not None:
            if self.root is None or self.rig is None:
                raise ValueError("ClipMotion with rotations also needs root and rig")
            j = self.rig.num_joints
            if self.rotations.shape != (n, j, 4) or self.root.shape != (n, 3):
                raise ValueError(
                    f"ClipMotion: rotations {self.rotations.shape} / root {self.root.shape} do not match "
                    f"{n} frames and the rig's {j} joints"
                )

    @property
    def num_frames(self) -> int:
        return len(self.joints)

    @property
    def has_rotations(self) -> bool:
        return self.rotations is not None

    @property
    def bone_offsets(self) -> np.ndarray:
        if self.rig is None:
            raise ValueError("this clip has no rotation rig")
        return self.rig.offsets if self.offsets is None else self.offsets

    def rig_positions(self) -> np.ndarray:
        """(N, J, 3) world positions of the rig's joints: FK of rotations, root and this clip's offsets."""
        if self.rotations is None:
            raise ValueError("this clip has no local rotations (the dataset stores joint positions only)")
        translations = np.broadcast_to(self.bone_offsets, self.rotations.shape[:-1] + (3,)).copy()
        translations[:, 0] = self.root
        return forward_kinematics(self.rotations, translations, self.rig.parents)[0]


@dataclass
class LabelledClip:
    """A clip with what conditions it: captions (GENERATED ones must say so in meta), an action id, its id."""

    id: str
    motion: ClipMotion
    texts: list[str]
    action: int = -1  # motiondiff.data.datasets.NO_ACTION
    meta: dict | None = None


@dataclass
class ClipSplit:
    """One split of a dataset as loaders return it; datamodules encode it with the configured representation."""

    clips: list[LabelledClip]
    action_names: list[str]
    fps: float
    feature_skeleton: Skeleton  # skeleton of ClipMotion.joints (SMPL-22 or KIT-21)
    rig: Skeleton | None = None  # rotation skeleton (mean offsets of the TRAIN split), None without rotations
