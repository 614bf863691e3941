"""HumanML3D features (263 for SMPL-22, 251 for KIT-21) as a Representation, with a torch port of
features.joints_from_features so the geometric losses can backpropagate through the decoding.

Row i of the features describes frame i (positions, root height, rotations) plus the step to frame i+1
(velocities), so a clip of N frames gives N-1 rows and decoding them gives frames 0..N-2 of the canonical joints.
"""

from __future__ import annotations

import numpy as np
import torch

from motiondiff.data.representations.base import Representation, contact_joints_of
from motiondiff.data.representations.clip import ClipMotion
from motiondiff.data.representations.hml_features import feature_dim, feature_slices, features_from_canonical, mean_std
from motiondiff.geometry.skeleton import Skeleton
from motiondiff.geometry.torch_rotations import qinv, qrot


def recover_root_torch(features: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Root rotation quaternions (..., N, 4) and positions (..., N, 3): torch twin of features.recover_root."""
    zero = torch.zeros_like(features[..., :1, 0])
    # integrate the stored half-angle velocity about y (frame 0 faces +Z)
    half_angle = torch.cat([zero, torch.cumsum(features[..., :-1, 0], dim=-1)], dim=-1)
    r_rot = torch.stack([torch.cos(half_angle), zero.expand_as(half_angle), torch.sin(half_angle),
                         zero.expand_as(half_angle)], dim=-1)  # fmt: skip
    # the x/z velocity is stored in the facing frame of the next frame: turn it back to world and sum it up
    vel = features[..., :-1, 1:3]
    step = torch.stack([vel[..., 0], torch.zeros_like(vel[..., 0]), vel[..., 1]], dim=-1)
    step = torch.cat([torch.zeros_like(step[..., :1, :]), step], dim=-2)
    r_pos = torch.cumsum(qrot(qinv(r_rot), step), dim=-2)
    r_pos = torch.stack([r_pos[..., 0], features[..., 3], r_pos[..., 2]], dim=-1)
    return r_rot, r_pos


class HMLRepresentation(Representation):
    """`hml263` (SMPL-22) / `kit251` (KIT-21): features.features_from_canonical of the clip's canonical joints."""

    frames_dropped = 1
    needs_rotations = False

    def __init__(self, name: str, skeleton: Skeleton):
        self.name = name
        self.skeleton = skeleton
        self.dim = feature_dim(skeleton.num_joints)
        self.contact_joints = contact_joints_of(skeleton)
        self._slices = feature_slices(skeleton.num_joints)

    def encode(self, clip: ClipMotion) -> np.ndarray:
        self._check_clip_joints(clip)
        return features_from_canonical(clip.joints, self.skeleton)

    def decode(self, features: torch.Tensor, offsets: torch.Tensor | None = None) -> torch.Tensor:
        """Positions are stored directly in the features, so `offsets` is accepted for the common interface and
        ignored (the bone lengths are the ones the features were computed from)."""
        features = self._check_features(features)
        j = self.skeleton.num_joints
        r_rot, r_pos = recover_root_torch(features)
        local = features[..., self._slices["ric"]].reshape(features.shape[:-1] + (j - 1, 3))
        local = qrot(qinv(r_rot)[..., None, :], local)  # un-face: root-facing frame -> world
        shift = torch.stack([r_pos[..., 0], torch.zeros_like(r_pos[..., 0]), r_pos[..., 2]], dim=-1)
        return torch.cat([r_pos[..., None, :], local + shift[..., None, :]], dim=-2)

    def joint_dims(self) -> list[list[int]]:
        j, sl = self.skeleton.num_joints, self._slices
        ric, rot, vel, con = (range(sl[k].start, sl[k].stop) for k in ("ric", "rot6d", "local_vel", "contacts"))
        dims = [[0, 1, 2, 3, *vel[0:3]]]  # root: angular velocity, x/z velocity, height, its own velocity
        for k in range(1, j):
            dims.append([*ric[3 * (k - 1) : 3 * k], *rot[6 * (k - 1) : 6 * k], *vel[3 * k : 3 * k + 3]])
        for channel, joint in zip(con, self.contact_joints, strict=True):
            dims[joint].append(channel)  # each contact channel belongs to its foot joint
        return dims

    def foot_contacts(self, features: torch.Tensor, offsets: torch.Tensor | None = None) -> torch.Tensor:
        """The stored contact channels (> 0.5: also right for noisy generated features)."""
        features = self._check_features(features)
        return (features[..., self._slices["contacts"]] > 0.5).to(features.dtype)

    def mean_std(self, features: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """HumanML3D's own statistics (Mean.npy/Std.npy: block-averaged std)."""
        return mean_std(np.asarray(features).reshape(-1, self.dim), self.skeleton.num_joints)
