"""Export motions as BVH files on a project skeleton (SMPL-22, KIT-21 or a dataset's rig), for Blender, MotionBuilder
and other animation tools.

Units: the file holds the input's units (metres in this project) times `scale` (e.g. scale=100 for a centimetre
file); `read_bvh` gives file units back, so `read_bvh(path).scaled(1 / scale)` returns metres. Joints keep the
skeleton's names (whitespace turned into '_', which BVH cannot hold); the file lists them depth-first, so look
them up by name after reading. Channels: root 'Xposition Yposition Zposition Zrotation Xrotation Yrotation',
other joints 'Zrotation Xrotation Yrotation'. End Sites: every leaf (SMPL-22's head, toes and wrists) gets one with a
real length, so animation tools draw the leaf's bone (a zero End Site makes Blender warn "zero length node"):
`Skeleton.end_sites`, along the leaf's own bone, as long as the top of the head (0.065 H), the toes past the ball
of the foot (0.041 H) and the hand (0.108 H) of a body of standing height H estimated from the leg (anatomical
proportions of Drillis & Contini, see `motiondiff.geometry.skeleton.END_SITE_STATURE`).

Every export reports its fit error: the distance between the written motion's forward kinematics and the joints
it was made from (metres, before `scale`).
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from motiondiff.data.formats.bvh import motion_from_arrays, write_bvh
from motiondiff.data.representations import RotationRepresentation  # torch: only when features are exported
from motiondiff.export.pose_inputs import PoseInputs
from motiondiff.export.rig_names import with_rig_names
from motiondiff.geometry.inverse_kinematics import fit_rest_offsets, fit_rotations, solve_rotations
from motiondiff.geometry.motion_checks import check_motion
from motiondiff.geometry.rotations import matrix_to_quat
from motiondiff.geometry.skeleton import Skeleton

if TYPE_CHECKING:
    from motiondiff.data.representations import Representation

__all__ = ["ExportReport", "export_bvh", "export_bvh_from_features"]

TWIST_HALF_LIFE_S = 1.0  # seconds for a twist carried through a swing singularity to fade by half (see IK)


@dataclass(frozen=True)
class ExportReport:
    """Where an exported file (a BVH, or SMPL parameters: smpl_export) went and how closely it reproduces the joints
    (metres): max and mean over frames and joints of |FK(file motion) - joints|. Usable as a path (os.fspath)."""

    path: Path
    max_error: float
    mean_error: float
    frames: int
    method: str  # "rotations" (written as given) or "ik" (solved from positions)

    def __fspath__(self) -> str:
        return str(self.path)


def export_bvh(
    path: str | os.PathLike,
    joints: np.ndarray,
    skeleton: Skeleton,
    fps: float,
    *,
    scale: float = 1.0,
    **pose: np.ndarray | None,
) -> ExportReport:
    """Write joints (N, J, 3) (metres, y up, the skeleton's joint order) as a BVH on `skeleton`.

    ``pose``: `rotations`, `root`, `offsets` (`export.pose_inputs.PoseInputs`, which checks them). With `rotations`
    (N, J, 4) local quaternions (w, x, y, z; the root's global) and `root` (N, 3) positions, as a rotation
    representation gives them, those are written as they are, on `offsets` (default: the skeleton's).
    Otherwise the rotations are solved by inverse kinematics on `offsets`, by default the motion's own bone lengths
    and sibling arrangement (`fit_rest_offsets`), which makes the fit exact up to float precision for any motion of
    rigid bones; joints whose bones stretch (generated motion) then get rotations and bone lengths fitted to keep the
    worst joint close (`inverse_kinematics.fit_rotations`). Given `offsets` are kept as they are. The file is written
    atomically (nothing is left behind on failure)."""
    joints = check_motion(
        joints,
        skeleton,
        fps,
        "export_bvh",
        "decode features first (Representation.decode_numpy) and pass one motion at a time",
    )
    if not (np.isfinite(scale) and scale > 0):
        raise ValueError(f"export_bvh: scale must be a positive number (100 for a centimetre file), got {scale}")
    rotations, root, offsets = PoseInputs.checked("export_bvh", joints, skeleton, pose)
    if rotations is not None:
        method = "rotations"
    else:
        half_life = TWIST_HALF_LIFE_S * fps
        if offsets is None:  # the motion's own skeleton, polished where its bones stretch
            rotations, root, offsets = fit_rotations(joints, skeleton, fit_rest_offsets(joints, skeleton),
                                                     twist_half_life=half_life)  # fmt: skip
        else:
            rotations, root = solve_rotations(joints, skeleton, offsets, twist_half_life=half_life)
        method = "ik"
    names = [re.sub(r"\s+", "_", n) for n in skeleton.joint_names]
    end_sites = {j: site * scale for j, site in skeleton.end_sites(offsets).items()}
    motion = motion_from_arrays(
        names, skeleton.parents, offsets * scale, rotations, root * scale, fps, end_sites=end_sites, source=str(path)
    )
    distance = np.linalg.norm(motion.positions() / scale - joints, axis=-1)
    write_bvh(path, motion)
    return ExportReport(Path(path), float(distance.max()), float(distance.mean()), len(joints), method)


def export_bvh_from_features(
    path: str | os.PathLike,
    representation: Representation,
    features: np.ndarray,
    fps: float,
    *,
    offsets: np.ndarray | None = None,
    scale: float = 1.0,
    names: str | None = None,
) -> ExportReport:
    """Write de-normalised features (N, D) of `representation` as a BVH on its skeleton: a rotation representation's
    own rotations and root (no IK; `offsets` default to the rig's mean offsets), else the decoded joints through IK.
    The fit error is measured against the representation's own decoding. ``names``: a rig's bone names
    (export.rig_names: smpl, mixamo) instead of the skeleton's."""

    features = np.asarray(features, dtype=np.float64)
    if features.ndim != 2 or features.shape[1] != representation.dim or len(features) == 0:
        raise ValueError(
            f"export_bvh_from_features: {representation.name} features must have shape (frames, "
            f"{representation.dim}) for one motion, got {features.shape}; de-normalise and pass one sample at a time"
        )
    if not np.isfinite(features).all():
        raise ValueError("export_bvh_from_features: features contain NaN or Inf; the sample diverged, resample it")
    skeleton = with_rig_names(representation.skeleton, names)
    joints = representation.decode_numpy(features, offsets)
    if isinstance(representation, RotationRepresentation):
        import torch

        with torch.no_grad():
            matrices = representation.rotation_matrices(torch.as_tensor(features)).numpy()
        # scipy's from_matrix takes the nearest rotation, so raw 9-number matrices (rpmjr) also give rotations
        rotations = matrix_to_quat(matrices)
        rig_offsets = skeleton.offsets if offsets is None else offsets
        return export_bvh(
            path, joints, skeleton, fps, rotations=rotations, root=features[:, :3], offsets=rig_offsets, scale=scale
        )
    return export_bvh(path, joints, skeleton, fps, offsets=offsets, scale=scale)
