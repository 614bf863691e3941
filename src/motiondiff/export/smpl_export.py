"""Export motions as SMPL pose parameters (`.npz` in the layout of AMASS and the SMPL/SMPL-X Blender add-ons), for
tools that drive an SMPL body: 24 joints' axis-angle rotations plus a root translation.

Conventions (those of the SMPL model itself, and of HumanML3D):
- y up, the body facing +z in the rest pose, its left side at +x; metres;
- joints in SMPL order (pelvis, l_hip, r_hip, spine1, ..., l_wrist, r_wrist, l_hand, r_hand): SMPL-22 is SMPL's
  first 22 joints, so a SMPL-22 motion's rotations fill rows 0-21 and the two hands (22, 23) stay at zero;
- `poses[:, 3j:3j+3]` is joint j's rotation relative to its parent (joint 0's, `global_orient`, is the root's
  global one), on SMPL's rest pose: the rest offsets the file records point the way the SMPL template's bones do;
- the pelvis is at `trans + rest_offsets[0]`, with `rest_offsets[0]` the SMPL neutral template's rest pelvis, so
  `trans` means what it means to an SMPL model with zero shape (an SMPL body puts its pelvis at J_0(betas) + trans).

The file also records what is needed to get the joints back without the (licence-restricted) SMPL model:
`rest_offsets` (24, 3) (row 0 the rest pelvis, the others each joint's offset from its parent), `rest_joints`
(24, 3), `parents` (24,) and `joint_names`; `smpl_joints` runs that forward kinematics. The bone lengths are the
motion's own (not an SMPL body shape: `betas` are zeros, the mean shape), so a real SMPL body shows the pose on its
own proportions. Rotations are the model's own where its representation has rotations on a SMPL rig, else solved by
inverse kinematics from the joints (the twist of a single-child bone about itself is not observable from positions;
it is kept continuous, as in the BVH export). Generated joints stretch their bones from frame to frame, which no
fixed skeleton can follow; for them rotations and bone lengths are fitted to keep the worst joint close (the fit
error is in the export's report). AMASS's own files are z up: rotate `global_orient` and the pelvis by +90 degrees
about x to get there; the SMPL-X Blender add-on reads this y-up layout with its "SMPL-X" format.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from motiondiff.data.representations import RotationRepresentation  # torch: only when features are exported
from motiondiff.export.bvh_export import TWIST_HALF_LIFE_S, ExportReport
from motiondiff.export.pose_inputs import PoseInputs
from motiondiff.geometry.inverse_kinematics import fit_rest_offsets, fit_rotations
from motiondiff.geometry.kinematics import forward_kinematics
from motiondiff.geometry.motion_checks import check_motion
from motiondiff.geometry.rotations import matrix_to_quat, quat_to_rotvec, rotvec_to_quat
from motiondiff.geometry.skeleton import SMPL22, SMPL24, Skeleton
from motiondiff.runtime.atomic import atomic_write
from motiondiff.runtime.errors import UsageError

if TYPE_CHECKING:
    from motiondiff.data.representations import Representation

__all__ = ["SMPL_NEUTRAL_PELVIS", "SmplLayoutError", "check_smpl_skeleton", "export_smpl",
           "export_smpl_from_features", "smpl_joints", "smpl_parameters"]  # fmt: skip

# Rest position of the pelvis (J_0) of the SMPL neutral template at zero shape, metres, rounded like the template
# offsets in skeleton.SMPL24_REST_OFFSETS.
SMPL_NEUTRAL_PELVIS = np.array([-0.0018, -0.2233, 0.0282])
NUM_BETAS = 10
SUPPORTED = "SMPL-22 (the HumanML3D skeleton of hml263 models) or SMPL-24 (the SMPL rig of HumanAct12/UESTC)"


class SmplLayoutError(UsageError):
    """The motion's skeleton is not one SMPL's joints can be read from."""


def check_smpl_skeleton(
    skeleton: Skeleton, purpose: str = "export=smpl", instead: str = "export it as bvh (any skeleton) instead"
) -> int:
    """22 or 24: how many SMPL joints the skeleton has (its joints are SMPL's first ones, in SMPL's order);
    SmplLayoutError naming what is supported (for `purpose`) and what to do `instead` otherwise."""
    parents = tuple(int(p) for p in skeleton.parents)
    for layout in (SMPL24, SMPL22):
        if parents == tuple(layout.parents):
            return layout.num_joints
    raise SmplLayoutError(
        f"{purpose} needs a motion on {SUPPORTED}; this one is on {skeleton.name!r} ({skeleton.num_joints} "
        f"joints): {instead}"
    )


def export_smpl(path: str | os.PathLike, joints: np.ndarray, skeleton: Skeleton, fps: float, **pose) -> ExportReport:
    """Write joints (N, J, 3) (metres, y up) of a SMPL-22 or SMPL-24 skeleton as SMPL parameters to `path` (.npz):
    the arrays of `smpl_parameters` (``pose``: its `rotations`, `root`, `offsets`). The report's error is
    |FK(file) - joints| (metres) over frames and joints. Written atomically."""
    data, distance, method = smpl_parameters(joints, skeleton, fps, **pose)
    atomic_write(path, lambda tmp: np.savez(tmp, **data), suffix=".npz")
    return ExportReport(Path(path), float(distance.max()), float(distance.mean()), len(data["poses"]), method)


def smpl_parameters(
    joints: np.ndarray, skeleton: Skeleton, fps: float, **pose: np.ndarray | None
) -> tuple[dict, np.ndarray, str]:
    """The SMPL parameters of joints (N, J, 3) (metres, y up) of a SMPL-22 or SMPL-24 skeleton, without writing
    them: (the file's arrays, |FK(arrays) - joints| (N, J) in metres, "rotations" or "ik").

    ``pose``: `rotations`, `root`, `offsets` (`export.pose_inputs.PoseInputs`, which checks them). With `rotations`
    (N, J, 4) (local quaternions w, x, y, z; the root's global) and `root` (N, 3), as a rotation representation
    gives them, those are used on `offsets` (default: the skeleton's). Otherwise they are solved by IK on SMPL's
    rest directions with the motion's own bone lengths and pelvis/chest arrangement, exact for rigid bones; when the
    joints stretch their bones (generated motion) rotations and bone lengths are then fitted to keep the worst
    joint as close as a fixed skeleton can (`refine_rotations`)."""
    count = check_smpl_skeleton(skeleton)
    joints = check_motion(joints, skeleton, fps, "export_smpl")
    rotations, root, offsets = PoseInputs.checked("export_smpl", joints, skeleton, pose)
    if rotations is not None:
        method = "rotations"
    else:
        rest = _smpl_rest(count)
        offsets = fit_rest_offsets(joints, rest) if offsets is None else offsets
        # polished where the bones are not rigid (generated joints)
        rotations, root, offsets = fit_rotations(joints, rest, offsets, twist_half_life=TWIST_HALF_LIFE_S * fps)
        method = "ik"
    data = _smpl_arrays(rotations, root, offsets, fps)
    return data, np.linalg.norm(smpl_joints(data)[:, :count] - joints, axis=-1), method


def export_smpl_from_features(
    path: str | os.PathLike, representation: Representation, features: np.ndarray, fps: float
) -> ExportReport:
    """De-normalised features (N, D) as SMPL parameters: a rotation representation's own rotations and root on its
    rig's mean offsets, else the decoded joints through IK."""

    check_smpl_skeleton(representation.skeleton)
    features = np.asarray(features, dtype=np.float64)
    if features.ndim != 2 or features.shape[1] != representation.dim or len(features) == 0:
        raise ValueError(f"export_smpl_from_features: {representation.name} features must have shape (frames, "
                         f"{representation.dim}) for one motion, got {features.shape}")  # fmt: skip
    joints = representation.decode_numpy(features)
    if not isinstance(representation, RotationRepresentation):
        return export_smpl(path, joints, representation.skeleton, fps)
    import torch

    with torch.no_grad():
        matrices = representation.rotation_matrices(torch.as_tensor(features)).numpy()
    return export_smpl(path, joints, representation.skeleton, fps, rotations=matrix_to_quat(matrices),
                       root=features[:, :3])  # fmt: skip


def smpl_joints(data: Mapping) -> np.ndarray:
    """The 24 joints (F, 24, 3) of a file written by `export_smpl` (np.load's result or a dict): forward
    kinematics of `poses` over `parents` with `rest_offsets`, the pelvis at `trans + rest_offsets[0]`."""
    poses = np.asarray(data["poses"], dtype=np.float64)
    frames = len(poses)
    local = rotvec_to_quat(poses.reshape(frames, -1, 3))
    translations = np.repeat(np.asarray(data["rest_offsets"], dtype=np.float64)[None], frames, axis=0)
    translations[:, 0] += np.asarray(data["trans"], dtype=np.float64)
    return forward_kinematics(local, translations, np.asarray(data["parents"]))[0]


def _smpl_rest(count: int) -> Skeleton:
    """The SMPL-22/24 skeleton with the SMPL template's rest offsets: IK solves rotations relative to SMPL's rest
    pose (bone directions of the template, lengths of the motion)."""
    return (SMPL24 if count == 24 else SMPL22).with_offsets(SMPL24.offsets[:count])


def _smpl_arrays(rotations: np.ndarray, root: np.ndarray, offsets: np.ndarray, fps: float) -> dict:
    """The .npz contents for local rotations (N, 22 or 24, 4), root positions and rest offsets of those joints."""
    frames, count = rotations.shape[:2]
    local = np.zeros((frames, 24, 4))
    local[..., 0] = 1.0  # joints the motion lacks (SMPL-22: the hands) keep the rest pose
    local[:, :count] = rotations
    rest = np.zeros((24, 3))
    rest[:count] = offsets
    if count < 24:  # the hands: the template's offsets, scaled by the motion's forearms against the template's
        forearms = np.linalg.norm(offsets[[20, 21]], axis=-1).sum()
        rest[count:] = SMPL24.offsets[count:] * forearms / np.linalg.norm(SMPL24.offsets[[20, 21]], axis=-1).sum()
    rest[0] = SMPL_NEUTRAL_PELVIS
    poses = quat_to_rotvec(local).reshape(frames, 72)
    trans = root - SMPL_NEUTRAL_PELVIS
    rest_joints = forward_kinematics(np.tile([1.0, 0.0, 0.0, 0.0], (24, 1)), rest, SMPL24.parents)[0]
    return {
        "poses": poses, "trans": trans, "mocap_framerate": np.array(float(fps)), "gender": np.array("neutral"),
        "betas": np.zeros(NUM_BETAS), "global_orient": poses[:, :3], "body_pose": poses[:, 3:], "transl": trans,
        "rest_offsets": rest, "rest_joints": rest_joints, "parents": np.array(SMPL24.parents, dtype=np.int64),
        "joint_names": np.array(SMPL24.joint_names), "up_axis": np.array("y"),
    }  # fmt: skip
