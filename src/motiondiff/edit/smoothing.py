"""vvMDM's temporal smoothing: a Gaussian filter over time on generated motion removes jitter (vvMDM §4, App. A.6).

    x̃_t = Σ_k w_k x_{t+k},   w_k = exp(−k² / 2σ²) / Σ_k' exp(−k'² / 2σ²),   |k| ≤ ⌈4σ⌉,

per joint coordinate, σ in frames, ends padded by repeating the first/last frame (so a motion does not sag towards
zero at its ends).

Why on decoded joint positions and not on features: joints are what every representation decodes to and what is
saved and rendered, and a low-pass filter on positions is a plain average of points, which commutes with where the
motion stands. The same filter on features would mean different things per representation: averaging quaternions,
Euler or axis-angle values component-wise is not a rotation average (and breaks at sign flips and ±π wraps), and
on hml263 it would blur root velocities that are then integrated, moving the whole path. The cost: an average of
points on an arc lies inside the arc, so a bone turning at ω rad per frame shortens by ≈ σ²ω²/2 of its length
(0.5 % for σ = 2 frames and 1 rad/s at 20 fps; keep σ small).

The effect is measured with the project's smoothness metric (vvMDM eq. 16, ``eval.metrics.smoothness``) in the space
evaluate.py uses: the HumanML3D features of the joints (``smoothness_of_joints``).
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import gaussian_filter1d

from motiondiff.data.representations.hml_features import (
    canonicalize_joints,
    features_from_canonical,
    features_from_joints,
    joints_from_features,
    skeleton_for_dim,
)
from motiondiff.geometry.skeleton import Skeleton

MIN_FRAMES = 4  # HumanML3D features drop one frame; the metric's second difference needs three rows


def smooth_joints(joints: np.ndarray, sigma: float | None) -> np.ndarray:
    """Joints (..., T, J, 3) filtered over time with a Gaussian of ``sigma`` frames; None or 0 returns a copy."""
    joints = np.asarray(joints)
    if sigma is None or sigma == 0:
        return joints.copy()
    if not sigma > 0:
        raise ValueError(f"smoothing sigma must be >= 0 frames (0 or null: off), got {sigma}")
    out = gaussian_filter1d(joints.astype(np.float64), float(sigma), axis=-3, mode="nearest")
    return out.astype(joints.dtype)


def smoothness_of_joints(joints: np.ndarray, skeleton: Skeleton, alpha: float = 1.0) -> float | None:
    """vvMDM smoothness (1 = no acceleration) of one motion (T, J, 3) of a HumanML3D skeleton (SMPL-22 / KIT-21),
    measured on its HumanML3D features as evaluate.py does; None for motions too short to measure."""
    if len(joints) < MIN_FRAMES:
        return None
    from motiondiff.metrics import smoothness  # torchmetrics (2 s to import): not for every sampling command

    feats = features_from_canonical(canonicalize_joints(joints, skeleton), skeleton)
    return smoothness(feats, alpha)


SMOOTHABLE = ("hml263", "kit251", "jp")  # layouts whose features give joint positions back without IK


def smooth_features(features: np.ndarray, sigma: float | None, layout: str = "hml263") -> np.ndarray:
    """Features (T, D) of one motion with its joints smoothed (``smooth_joints``): HumanML3D features are decoded,
    filtered and re-encoded (the same T rows; the last frame is repeated once, as the encoding drops one); `jp`
    features are joint positions, filtered as they are. None or 0 returns a copy. Evaluation applies the filter
    here so that the metrics see the motion sample.py saves with the same ``smooth_sigma``. Rotation layouts are
    refused: averaging rotation components is not a rotation average, and positions cannot be re-encoded as
    rotations without inverse kinematics."""
    features = np.asarray(features)
    if sigma is None or sigma == 0 or len(features) < 2:
        return features.copy()
    if layout not in SMOOTHABLE:
        raise ValueError(f"temporal smoothing of {layout} features is not defined here; use one of {SMOOTHABLE}")
    if layout == "jp":
        return smooth_joints(features.reshape(len(features), -1, 3), sigma).reshape(features.shape)
    joints = smooth_joints(joints_from_features(features), sigma)
    joints = np.concatenate([joints, joints[-1:]], axis=0)
    return features_from_joints(joints, skeleton_for_dim(features.shape[-1])).astype(features.dtype)
