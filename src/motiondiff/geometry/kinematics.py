"""Forward kinematics for any tree skeleton (numpy; quaternions (w, x, y, z))."""

from __future__ import annotations

import numpy as np

from motiondiff.geometry.rotations import qmul, qrot


def forward_kinematics(
    local_rotations: np.ndarray, local_translations: np.ndarray, parents
) -> tuple[np.ndarray, np.ndarray]:
    """Local joint rotations (..., J, 4) and translations from the parent (..., J, 3) -> world positions and
    world rotations. The root's translation is its world position. Joints must be ordered parents first."""
    parents = np.asarray(parents)
    positions = np.empty(local_translations.shape, dtype=np.float64)
    rotations = np.empty(local_rotations.shape, dtype=np.float64)
    for j, p in enumerate(parents):
        if p < 0:
            positions[..., j, :] = local_translations[..., j, :]
            rotations[..., j, :] = local_rotations[..., j, :]
        else:
            positions[..., j, :] = positions[..., p, :] + qrot(rotations[..., p, :], local_translations[..., j, :])
            rotations[..., j, :] = qmul(rotations[..., p, :], local_rotations[..., j, :])
    return positions, rotations


def forward_kinematics_torch(local_rotations, local_translations, parents):
    """Differentiable FK in torch: local rotation MATRICES (..., J, 3, 3) and translations from the parent
    (..., J, 3) -> world positions (..., J, 3) and world rotation matrices (..., J, 3, 3). The root's translation
    is its world position; joints must be ordered parents first. Works in the inputs' dtype and device."""
    import torch  # imported here so the numpy-only data pipeline does not pay for torch

    shape = torch.broadcast_shapes(local_rotations.shape[:-2], local_translations.shape[:-1])
    rot = local_rotations.expand(shape + (3, 3))
    trans = local_translations.expand(shape + (3,))
    positions, world = [], []  # lists, not in-place writes, so autograd sees a plain graph
    for j, p in enumerate(parents):
        if p < 0:
            positions.append(trans[..., j, :])
            world.append(rot[..., j, :, :])
        else:
            positions.append(positions[p] + (world[p] @ trans[..., j, :, None])[..., 0])
            world.append(world[p] @ rot[..., j, :, :])
    return torch.stack(positions, dim=-2), torch.stack(world, dim=-3)
