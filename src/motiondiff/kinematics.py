"""Forward kinematics for any tree skeleton (numpy; quaternions (w, x, y, z))."""

from __future__ import annotations

import numpy as np

from motiondiff.rotations import qmul, qrot


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
