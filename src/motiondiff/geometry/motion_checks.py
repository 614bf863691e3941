"""The one check every consumer of a motion makes (exports, cleanups): joints (frames, J, 3) on the skeleton, finite,
at a positive frame rate. Each caller names itself (`who`) and what to do about a wrong shape (`shape_hint`), so the
messages stay specific while the rules exist once."""

from __future__ import annotations

import numpy as np

from motiondiff.geometry.skeleton import Skeleton


def check_motion(
    joints, skeleton: Skeleton, fps: float | None, who: str, shape_hint: str = "pass one motion at a time"
) -> np.ndarray:
    """`joints` as float64 (N >= 1, J, 3), or ValueError naming `who`, the bad frames and the fix. `fps=None`:
    not checked (the caller has no frame rate)."""
    raw = np.asarray(joints)
    if raw.dtype.kind in "iubcUSV":  # whole numbers, flags, text: not positions ("NaN or Inf" would mislead)
        raise ValueError(f"{who}: joints hold {raw.dtype}, expected floating-point positions in metres (float32 "
                         "or float64)")  # fmt: skip
    joints = raw.astype(np.float64)
    j = skeleton.num_joints
    if joints.ndim != 3 or joints.shape[1:] != (j, 3) or len(joints) == 0:
        raise ValueError(f"{who}: joints must have shape (frames >= 1, {j}, 3) for skeleton {skeleton.name!r}, got "
                         f"{joints.shape}; {shape_hint}")  # fmt: skip
    bad = ~np.isfinite(joints).all(axis=(1, 2))
    if bad.any():
        raise ValueError(f"{who}: joints contain NaN or Inf in {int(bad.sum())} frame(s) (first: "
                         f"{int(np.argmax(bad))}); the motion diverged, resample it or drop those frames")  # fmt: skip
    if fps is not None and not (isinstance(fps, int | float | np.number) and np.isfinite(fps) and fps > 0):
        raise ValueError(f"{who}: fps must be a positive number, got {fps}")
    return joints
