"""The `Representation` interface: one object owns a feature layout (encode, differentiable decode, which dims
belong to which joint, foot contacts, normalisation statistics). Losses, editing masks and samplers ask it; nothing
else hard-codes feature dims."""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np
import torch

from motiondiff.data.representations.clip import ClipMotion
from motiondiff.data.representations.hml_features import FOOT_CONTACT_THRESHOLD
from motiondiff.geometry.skeleton import Skeleton

STD_FLOOR = 1e-8  # a per-dim std below this (constant dim, e.g. a joint that never moves) is replaced by 1


class Representation(ABC):
    """Abstract feature layout. Subclasses set name, skeleton, dim, frames_dropped, needs_rotations and
    contact_joints, and implement encode / decode / joint_dims."""

    name: str
    skeleton: Skeleton  # joints that decode() returns
    dim: int  # feature width
    frames_dropped: int = 0  # rows encode() returns = frames - frames_dropped
    needs_rotations: bool = False
    contact_joints: tuple[int, ...] = ()  # joints of `skeleton` (left feet..., right feet...) for the contact loss

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.name!r}, dim={self.dim}, skeleton={self.skeleton.name!r})"

    # ---- encode / decode --------------------------------------------------------------------------------------
    @abstractmethod
    def encode(self, clip: ClipMotion) -> np.ndarray:
        """(N - frames_dropped, dim) float32 features of one clip, not normalised."""

    @abstractmethod
    def decode(self, features: torch.Tensor, offsets: torch.Tensor | None = None) -> torch.Tensor:
        """De-normalised features (..., N, dim) -> joint positions (..., N, J, 3) in metres, differentiable."""

    def decode_numpy(self, features: np.ndarray, offsets=None) -> np.ndarray:
        """float64 numpy convenience wrapper around `decode` (no gradients)."""
        feats = torch.as_tensor(np.asarray(features, dtype=np.float64))
        off = None if offsets is None else torch.as_tensor(np.asarray(offsets, dtype=np.float64))
        with torch.no_grad():
            return self.decode(feats, off).numpy()

    @abstractmethod
    def joint_dims(self) -> list[list[int]]:
        """Per joint of `skeleton`, the feature dims that describe it (the root's list holds the trajectory dims)."""

    def part_keep(self, joints) -> np.ndarray:
        """(D,) bool over the feature dims: True on every dim of the given joints (the root's include the
        trajectory: its velocities or position and, for HumanML3D, its height)."""
        dims = self.joint_dims()
        keep = np.zeros(self.dim, dtype=bool)
        for j in joints:
            keep[dims[j]] = True
        return keep

    # ---- shared helpers ---------------------------------------------------------------------------------------
    def _check_features(self, features: torch.Tensor) -> torch.Tensor:
        if not isinstance(features, torch.Tensor):
            raise TypeError(f"{self.name}.decode expects a torch.Tensor, got {type(features).__name__}")
        if features.ndim < 2 or features.shape[-1] != self.dim:
            raise ValueError(
                f"{self.name} features must have shape (..., frames, {self.dim}), got {tuple(features.shape)}"
            )
        return features

    def _offsets(self, offsets, like: torch.Tensor) -> torch.Tensor:
        """Bone offsets as a tensor that broadcasts against (..., N, J, 3): (J, 3) or (..., 1, J, 3)."""
        j = self.skeleton.num_joints
        off = self.skeleton.offsets if offsets is None else offsets
        off = torch.as_tensor(off, dtype=like.dtype, device=like.device)
        if off.ndim < 2 or off.shape[-2:] != (j, 3):
            raise ValueError(f"{self.name}: offsets must have shape (..., {j}, 3), got {tuple(off.shape)}")
        # per-clip offsets (..., J, 3) share the batch dims of the features, not the frame dim
        return off if off.ndim == 2 else off.unsqueeze(-3)

    def _check_clip_joints(self, clip: ClipMotion) -> None:
        j = self.skeleton.num_joints
        if clip.joints.ndim != 3 or clip.joints.shape[1:] != (j, 3):
            raise ValueError(
                f"{self.name}: clip joints have shape {clip.joints.shape}, expected (frames, {j}, 3) for the "
                f"{self.skeleton.name} skeleton"
            )

    # ---- foot contacts and statistics -------------------------------------------------------------------------
    def foot_contacts(self, features: torch.Tensor, offsets: torch.Tensor | None = None) -> torch.Tensor:
        """(..., N, len(contact_joints)) 0/1: squared per-frame displacement of the decoded contact joints below
        FOOT_CONTACT_THRESHOLD (the rule of features.foot_contacts); the last frame repeats the previous one."""
        pos = self.decode(features, offsets)[..., list(self.contact_joints), :]
        if pos.shape[-3] < 2:  # one frame: no displacement to measure, call it no contact
            return pos.new_zeros(pos.shape[:-1])
        disp = ((pos[..., 1:, :, :] - pos[..., :-1, :, :]) ** 2).sum(-1)
        contacts = (disp < FOOT_CONTACT_THRESHOLD).to(features.dtype)
        return torch.cat([contacts, contacts[..., -1:, :]], dim=-2)

    def mean_std(self, features: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Per-dim train statistics (float32); constant dims get std 1 so normalising them stays finite."""
        feats = np.asarray(features, dtype=np.float64).reshape(-1, self.dim)
        mean, std = feats.mean(axis=0), feats.std(axis=0)
        std = np.where(std < STD_FLOOR, 1.0, std)
        return mean.astype(np.float32), std.astype(np.float32)


def contact_joints_of(skeleton: Skeleton) -> tuple[int, ...]:
    """Left feet then right feet, the order features.foot_contacts uses."""
    return tuple(skeleton.foot_joints[0]) + tuple(skeleton.foot_joints[1])
