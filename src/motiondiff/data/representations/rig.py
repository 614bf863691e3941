"""The vvMDM representations on a rig: `jp` (world joint positions) and the five "root position + joint rotation"
layouts rp6jr / rpqjr / rpajr / rpejr / rpmjr.

Rotation layouts, per frame: [root position (3), rotation of joint 0 (k), ..., rotation of joint J-1 (k)], joint 0's
being the root's global rotation and the others local to their parents. (The paper zero-pads the root position to
one more "joint" of width k; a flat 3 + kJ row carries the same information without padding dims the network would
have to learn to keep at zero.) Decoding turns rotations into matrices and runs differentiable FK with the bone
offsets (the clip's when given, else the rig's mean offsets).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import torch
from scipy.spatial.transform import Rotation

from motiondiff.data.representations.base import Representation, contact_joints_of
from motiondiff.data.representations.clip import ClipMotion
from motiondiff.geometry import torch_rotations as tr
from motiondiff.geometry.kinematics import forward_kinematics_torch
from motiondiff.geometry.rotations import matrix_to_6d, matrix_to_euler, qfix, qnormalize, quat_to_matrix
from motiondiff.geometry.skeleton import Skeleton

# Intrinsic X-Y-Z. Each Tait-Bryan order locks when its MIDDLE angle reaches +-90 degrees. The Bandai rig's joint
# frames are not aligned with the world (bones run along local x), so several joints rest near a 90-degree turn
# about one axis. Measured on data/bandai_mini (train, share of frames with |middle angle| > 70 degrees): YXZ and
# ZXY put the Spine there in 99-100% of frames, XZY/YXZ/ZYX the shoulders in 76-100%, YZX/XZY the root in 89-97%;
# XYZ's worst joints are the feet (17-20%, full plantar flexion) and every other joint stays under 10%.
# Other rigs can pass their own order (`RotationRepresentation(name, rig, euler_order=...)`).
EULER_ORDER = "XYZ"


@dataclass(frozen=True)
class RotationCodec:
    width: int  # feature dims per joint
    encode: Callable[[np.ndarray, str], np.ndarray]  # unit quaternions (N, J, 4) float64 -> (N, J, width)
    decode: Callable[[torch.Tensor, str], torch.Tensor]  # (..., width) -> rotation matrices (..., 3, 3)


def _encode_quat(q: np.ndarray, order: str) -> np.ndarray:
    # QuaterNet's fix: frame 0 with w >= 0, then flip any frame whose dot with the previous one is negative
    q = np.where(q[:1, ..., :1] < 0, -q, q)
    return qfix(q, axis=0)


def _encode_axis_angle(q: np.ndarray, order: str) -> np.ndarray:
    xyzw = q[..., [1, 2, 3, 0]].reshape(-1, 4)
    return Rotation.from_quat(xyzw).as_rotvec().reshape(q.shape[:-1] + (3,))


CODECS: dict[str, RotationCodec] = {
    "rp6jr": RotationCodec(6, lambda q, o: matrix_to_6d(quat_to_matrix(q)), lambda x, o: tr.sixd_to_matrix(x)),
    "rpqjr": RotationCodec(4, _encode_quat, lambda x, o: tr.quat_to_matrix(x)),
    "rpajr": RotationCodec(3, _encode_axis_angle, lambda x, o: tr.axis_angle_to_matrix(x)),
    "rpejr": RotationCodec(
        3, lambda q, o: matrix_to_euler(quat_to_matrix(q), o, degrees=False), lambda x, o: tr.euler_to_matrix(x, o)
    ),
    "rpmjr": RotationCodec(
        9,
        lambda q, o: quat_to_matrix(q).reshape(q.shape[:-1] + (9,)),
        lambda x, o: x.reshape(x.shape[:-1] + (3, 3)),
    ),
}


def _check_rig_clip(rep: Representation, clip: ClipMotion) -> None:
    if not clip.has_rotations:
        raise ValueError(
            f"{rep.name} on rig {rep.skeleton.name!r} needs the clip's local rotations, but this clip has joint "
            "positions only; use hml263/kit251 or jp without a rig"
        )
    if clip.rig.num_joints != rep.skeleton.num_joints or tuple(clip.rig.parents) != tuple(rep.skeleton.parents):
        raise ValueError(
            f"{rep.name}: the clip's rig ({clip.rig.num_joints} joints) is not the representation's rig "
            f"{rep.skeleton.name!r} ({rep.skeleton.num_joints} joints)"
        )


class JointPositions(Representation):
    """`jp`: world joint positions flattened (N, 3J) - the rig's (FK with the clip's offsets) when there is a
    rig, else the clip's canonical feature-skeleton joints."""

    frames_dropped = 0
    needs_rotations = False

    def __init__(self, skeleton: Skeleton, uses_rig: bool):
        self.name = "jp"
        self.skeleton = skeleton
        self.uses_rig = uses_rig
        self.dim = 3 * skeleton.num_joints
        self.contact_joints = contact_joints_of(skeleton)

    def encode(self, clip: ClipMotion) -> np.ndarray:
        if self.uses_rig:
            _check_rig_clip(self, clip)
            pos = clip.rig_positions()
        else:
            self._check_clip_joints(clip)
            pos = clip.joints
        return np.asarray(pos, dtype=np.float32).reshape(len(pos), self.dim)

    def decode(self, features: torch.Tensor, offsets: torch.Tensor | None = None) -> torch.Tensor:
        """Positions are the features themselves; `offsets` is accepted for the common interface and ignored."""
        features = self._check_features(features)
        return features.reshape(features.shape[:-1] + (self.skeleton.num_joints, 3))

    def joint_dims(self) -> list[list[int]]:
        return [[3 * j, 3 * j + 1, 3 * j + 2] for j in range(self.skeleton.num_joints)]


class RotationRepresentation(Representation):
    """`rp{6,q,a,e,m}jr`: root position + every rig joint's rotation (root global, others local)."""

    frames_dropped = 0
    needs_rotations = True

    def __init__(self, name: str, rig: Skeleton, euler_order: str = EULER_ORDER):
        if name not in CODECS:
            raise ValueError(f"unknown rotation representation {name!r}; choose from {', '.join(CODECS)}")
        self.name = name
        self.skeleton = rig
        self.codec = CODECS[name]
        self.euler_order = euler_order.upper()
        self.dim = 3 + self.codec.width * rig.num_joints
        self.contact_joints = contact_joints_of(rig)

    def encode(self, clip: ClipMotion) -> np.ndarray:
        _check_rig_clip(self, clip)
        q = qnormalize(np.asarray(clip.rotations, dtype=np.float64))
        rot = self.codec.encode(q, self.euler_order).reshape(len(q), -1)
        return np.concatenate([np.asarray(clip.root, dtype=np.float64), rot], axis=-1).astype(np.float32)

    def rotation_matrices(self, features: torch.Tensor) -> torch.Tensor:
        """(..., N, dim) -> local rotation matrices (..., N, J, 3, 3) (root: global)."""
        features = self._check_features(features)
        rot = features[..., 3:].reshape(features.shape[:-1] + (self.skeleton.num_joints, self.codec.width))
        return self.codec.decode(rot, self.euler_order)

    def decode(self, features: torch.Tensor, offsets: torch.Tensor | None = None) -> torch.Tensor:
        features = self._check_features(features)
        mats = self.rotation_matrices(features)
        off = self._offsets(offsets, features)
        bones = off[..., 1:, :].expand(features.shape[:-1] + (self.skeleton.num_joints - 1, 3))
        translations = torch.cat([features[..., None, :3], bones], dim=-2)  # the root's is its world position
        return forward_kinematics_torch(mats, translations, self.skeleton.parents)[0]

    def joint_dims(self) -> list[list[int]]:
        k = self.codec.width
        dims = [list(range(3 + k * j, 3 + k * (j + 1))) for j in range(self.skeleton.num_joints)]
        dims[0] = [0, 1, 2, *dims[0]]  # the root owns the trajectory
        return dims
