"""The official HumanML3D motion features (263 for SMPL-22, 251 for KIT-21).

Follows the official procedure step by step (HumanML3D's motion_representation notebook), including its quirks,
so that features computed here match `new_joint_vecs` and features from the official data decode to `new_joints`:

    canonicalize_joints:  uniform skeleton -> floor at y=0 -> frame-0 root at the x,z origin -> facing +Z
    features_from_canonical: contacts, IK (smoothed facing), root velocities, local positions, 6D rotations, velocities

Layout of a row (J joints): [0] root angular velocity about y, [1:3] root x/z velocity, [3] root height,
[4 : 4+3(J-1)] root-relative positions, next 6(J-1) 6D local rotations, next 3J local velocities, last 4 contacts.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import gaussian_filter1d

from motiondiff.geometry.rotations import matrix_to_6d, qbetween, qinv, qmul, qnormalize, qrot, quat_to_matrix
from motiondiff.geometry.skeleton import KIT21, SMPL22, SMPL22_BONE_LENGTHS, Skeleton

UP = np.array([0.0, 1.0, 0.0])
FORWARD = np.array([0.0, 0.0, 1.0])
FOOT_CONTACT_THRESHOLD = 0.002  # squared displacement per frame (m^2) below which a foot joint is in contact
FACING_SMOOTH_SIGMA = 20  # frames; the official IK smooths the facing direction over time


def feature_dim(num_joints: int) -> int:
    return 4 + 3 * (num_joints - 1) + 6 * (num_joints - 1) + 3 * num_joints + 4


def skeleton_for_dim(dim: int) -> Skeleton:
    for skel in (SMPL22, KIT21):
        if feature_dim(skel.num_joints) == dim:
            return skel
    raise ValueError(f"features of width {dim} are neither HumanML3D (263, 22 joints) nor KIT-ML (251, 21 joints)")


def feature_slices(num_joints: int) -> dict[str, slice]:
    """Named blocks of a feature row (used by representations, editing masks and tests)."""
    j = num_joints
    b = [0, 1, 3, 4, 4 + 3 * (j - 1), 4 + 9 * (j - 1), 4 + 9 * (j - 1) + 3 * j, feature_dim(j)]
    names = ["root_rot_vel", "root_lin_vel", "root_y", "ric", "rot6d", "local_vel", "contacts"]
    return {n: slice(b[i], b[i + 1]) for i, n in enumerate(names)}


# ---- helpers ----------------------------------------------------------------------------------------------------
def _normalize(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _facing_rotation(across: np.ndarray) -> np.ndarray:
    """Quaternion turning the forward direction (up x across) to +Z."""
    forward = _normalize(np.cross(UP, _normalize(across)))
    return qbetween(forward, np.broadcast_to(FORWARD, forward.shape))


def _check_joints(joints: np.ndarray, skeleton: Skeleton) -> np.ndarray:
    joints = np.asarray(joints)
    if joints.ndim != 3 or joints.shape[1:] != (skeleton.num_joints, 3):
        raise ValueError(f"expected joints of shape (frames, {skeleton.num_joints}, 3), got {joints.shape}")
    if joints.shape[0] < 2:
        raise ValueError(f"need at least 2 frames to compute features, got {joints.shape[0]}")
    if not np.isfinite(joints).all():
        raise ValueError("joint positions contain NaN or Inf")
    return joints.astype(np.float64)


def inverse_kinematics(joints: np.ndarray, skeleton: Skeleton, smooth_facing: bool) -> np.ndarray:
    """Local joint quaternions (F, J, 4) whose bones point along the data, as the official IK computes them.

    Quirks kept on purpose (needed to match the official data): the hip term of the facing direction uses the
    opposite order to the canonicalisation step, frame 0's root rotation is identity, and every chain - also
    those that branch off the spine - starts from the root rotation.
    """
    r_hip, l_hip, r_sdr, l_sdr = skeleton.face_joints
    across = (joints[:, l_hip] - joints[:, r_hip]) + (joints[:, r_sdr] - joints[:, l_sdr])
    forward = np.cross(UP, _normalize(across))
    if smooth_facing:
        forward = gaussian_filter1d(forward, FACING_SMOOTH_SIGMA, axis=0, mode="nearest")
    forward = _normalize(forward)
    root = qbetween(forward, np.broadcast_to(FORWARD, forward.shape))
    root[0] = [1.0, 0.0, 0.0, 0.0]
    quats = np.zeros(joints.shape[:-1] + (4,))
    quats[:, 0] = root
    for chain in skeleton.kinematic_chains:
        parent_rot = root
        for a, b in zip(chain[:-1], chain[1:], strict=True):
            rest = np.broadcast_to(skeleton.raw_offsets[b], (len(joints), 3))
            bone = _normalize(joints[:, b] - joints[:, a])
            local = qmul(qinv(parent_rot), qbetween(rest, bone))
            quats[:, b] = local
            parent_rot = qmul(parent_rot, local)
    return quats


def _target_offsets(skeleton: Skeleton, joints0: np.ndarray, target_lengths: np.ndarray | None) -> np.ndarray:
    lengths = target_lengths
    if lengths is None:  # keep the input's own bone lengths (KIT: the official target skeleton is not shipped)
        lengths = _bone_lengths(joints0, skeleton)
    return skeleton.raw_offsets * lengths[:, None]


def _bone_lengths(frame: np.ndarray, skeleton: Skeleton) -> np.ndarray:
    parents = np.array(skeleton.parents)
    lengths = np.zeros(skeleton.num_joints)
    lengths[1:] = np.linalg.norm(frame[1:] - frame[parents[1:]], axis=-1)
    return lengths


def uniform_skeleton(joints: np.ndarray, skeleton: Skeleton, target_lengths: np.ndarray | None) -> np.ndarray:
    """Retarget to the dataset's target bone lengths: scale the root path by the leg-length ratio, IK, FK."""
    src = _bone_lengths(joints[0], skeleton)
    tgt_offsets = _target_offsets(skeleton, joints[0], target_lengths)
    tgt = np.linalg.norm(tgt_offsets, axis=-1)
    a, b = skeleton.leg_joints
    scale = (tgt[a] + tgt[b]) / (src[a] + src[b])
    quats = inverse_kinematics(joints, skeleton, smooth_facing=False)
    return chain_forward_kinematics(quats, joints[:, 0] * scale, tgt_offsets, skeleton)


def chain_forward_kinematics(quats: np.ndarray, root: np.ndarray, offsets: np.ndarray, skeleton: Skeleton):
    """The FK that inverts `inverse_kinematics`: along each chain the accumulated rotation *including the joint's
    own* turns that joint's rest offset (HumanML3D stores per joint the rotation of the bone that ends there)."""
    positions = np.zeros(quats.shape[:-1] + (3,))
    positions[:, 0] = root
    for chain in skeleton.kinematic_chains:
        rot = quats[:, 0]
        for a, b in zip(chain[:-1], chain[1:], strict=True):
            rot = qmul(rot, quats[:, b])
            positions[:, b] = positions[:, a] + qrot(rot, np.broadcast_to(offsets[b], (len(quats), 3)))
    return positions


def canonicalize_joints(
    joints: np.ndarray, skeleton: Skeleton = SMPL22, target_lengths: np.ndarray | None = "default"
) -> np.ndarray:
    """Steps 1-3 of the official procedure: the joints HumanML3D stores in `new_joints` (float64)."""
    joints = _check_joints(joints, skeleton)
    if isinstance(target_lengths, str):
        target_lengths = _default_lengths(skeleton)
    positions = uniform_skeleton(joints, skeleton, target_lengths)
    rotation, shift = ground_and_face(positions, skeleton)
    return qrot(np.broadcast_to(rotation, positions.shape[:-1] + (4,)), positions + shift)


def ground_and_face(positions: np.ndarray, skeleton: Skeleton) -> tuple[np.ndarray, np.ndarray]:
    """The rigid placement HumanML3D applies: p -> qrot(rotation, p + shift) puts the lowest joint of the clip on
    y = 0, frame 0's root at x = z = 0, and turns frame 0's facing to +Z. Returns (quaternion (4,), shift (3,))."""
    shift = -positions[0, 0] * np.array([1.0, 0.0, 1.0])
    shift[1] = -positions[..., 1].min()
    r_hip, l_hip, r_sdr, l_sdr = skeleton.face_joints
    first = positions[0]
    across = (first[r_hip] - first[l_hip]) + (first[r_sdr] - first[l_sdr])
    return _facing_rotation(across), shift


def _default_lengths(skeleton: Skeleton) -> np.ndarray | None:

    return SMPL22_BONE_LENGTHS if skeleton.name == "smpl22" else None


def foot_contacts(positions: np.ndarray, skeleton: Skeleton, threshold: float = FOOT_CONTACT_THRESHOLD) -> np.ndarray:
    """(F-1, 4) contacts of (left feet..., right feet...) from squared per-frame displacement."""
    feet = list(skeleton.foot_joints[0]) + list(skeleton.foot_joints[1])
    disp = ((positions[1:, feet] - positions[:-1, feet]) ** 2).sum(-1)
    return (disp < threshold).astype(np.float64)


def features_from_canonical(positions: np.ndarray, skeleton: Skeleton = SMPL22) -> np.ndarray:
    """Steps 4-6: (F, J, 3) canonical joints -> (F-1, D) float32 features."""
    positions = _check_joints(positions, skeleton)
    n = len(positions)
    contacts = foot_contacts(positions, skeleton)
    quats = inverse_kinematics(positions, skeleton, smooth_facing=True)
    r_rot = quats[:, 0]
    # Root: angular velocity (half-angle of the y rotation between frames) and velocity in the facing frame.
    r_vel_q = qmul(r_rot[1:], qinv(r_rot[:-1]))
    root_rot_vel = np.arcsin(r_vel_q[:, 2:3])
    root_lin_vel = qrot(r_rot[1:], positions[1:, 0] - positions[:-1, 0])[:, [0, 2]]
    root_y = positions[:-1, 0, 1:2]
    # Root-relative ("rifke") positions: remove root x/z, face +Z; joint 0 dropped.
    ric = positions.copy()
    ric[..., 0] -= positions[:, 0:1, 0]
    ric[..., 2] -= positions[:, 0:1, 2]
    ric = qrot(np.broadcast_to(r_rot[:, None], ric.shape[:-1] + (4,)), ric)
    ric = ric[:-1, 1:].reshape(n - 1, -1)
    rot6d = matrix_to_6d(quat_to_matrix(quats[:-1, 1:])).reshape(n - 1, -1)
    vel = qrot(np.broadcast_to(r_rot[:-1, None], (n - 1, skeleton.num_joints, 4)), positions[1:] - positions[:-1])
    vel = vel.reshape(n - 1, -1)
    feats = np.concatenate([root_rot_vel, root_lin_vel, root_y, ric, rot6d, vel, contacts], axis=-1)
    return feats.astype(np.float32)


def features_from_joints(joints: np.ndarray, skeleton: Skeleton = SMPL22) -> np.ndarray:
    """Raw joints (N, J, 3) in metres, y up -> official features (N-1, D) float32."""
    return features_from_canonical(canonicalize_joints(joints, skeleton), skeleton)


# ---- decoding ---------------------------------------------------------------------------------------------------
def recover_root(features: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Root rotation quaternions (N, 4) and root positions (N, 3) from rows (N, D) (works with any batch dims)."""
    half_angle = np.zeros(features.shape[:-1])
    half_angle[..., 1:] = np.cumsum(features[..., :-1, 0], axis=-1)
    r_rot = np.zeros(features.shape[:-1] + (4,))
    r_rot[..., 0] = np.cos(half_angle)
    r_rot[..., 2] = np.sin(half_angle)
    step = np.zeros(features.shape[:-1] + (3,))
    step[..., 1:, [0, 2]] = features[..., :-1, 1:3]
    r_pos = np.cumsum(qrot(qinv(r_rot), step), axis=-2)
    r_pos[..., 1] = features[..., 3]
    return qnormalize(r_rot), r_pos


def joints_from_features(features: np.ndarray, num_joints: int | None = None) -> np.ndarray:
    """Official features (..., N, D) -> joint positions (..., N, J, 3) float32 (the official recover_from_ric)."""
    features = np.asarray(features, dtype=np.float64)
    if features.ndim < 2:
        raise ValueError(f"expected features of shape (frames, dims), got {features.shape}")
    j = num_joints or skeleton_for_dim(features.shape[-1]).num_joints
    if features.shape[-1] != feature_dim(j):
        raise ValueError(f"features have width {features.shape[-1]}, expected {feature_dim(j)} for {j} joints")
    r_rot, r_pos = recover_root(features)
    local = features[..., feature_slices(j)["ric"]].reshape(features.shape[:-1] + (j - 1, 3))
    local = qrot(np.broadcast_to(qinv(r_rot)[..., None, :], local.shape[:-1] + (4,)), local)
    local[..., 0] += r_pos[..., None, 0]
    local[..., 2] += r_pos[..., None, 2]
    return np.concatenate([r_pos[..., None, :], local], axis=-2).astype(np.float32)


# ---- normalisation ----------------------------------------------------------------------------------------------
# Text-to-motion's evaluators (Guo et al. 2022, `feat_bias`) divide the std of the root and contact blocks by 5 so
# those few dims weigh more in the evaluator's input. The dataset's own Std.npy (HumanML3D) does not: models train on it.
EVALUATOR_STD_BIAS = 5.0
_ROOT_AND_CONTACT = ("root_rot_vel", "root_lin_vel", "root_y", "contacts")


def mean_std(features: np.ndarray, num_joints: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Mean/Std as HumanML3D's Mean.npy/Std.npy: per-dim mean; std averaged within each block (root rotation
    velocity, root linear velocity, root height, positions, rotations, velocities, contacts), nothing reweighted."""
    features = np.asarray(features, dtype=np.float64)
    j = num_joints or skeleton_for_dim(features.shape[-1]).num_joints
    mean = features.mean(axis=0)
    raw = features.std(axis=0)
    std = np.empty_like(raw)
    for sl in feature_slices(j).values():
        std[sl] = raw[sl].mean()
    return mean.astype(np.float32), std.astype(np.float32)


def evaluator_std(std: np.ndarray, num_joints: int | None = None) -> np.ndarray:
    """The T2M evaluator's normalisation from a dataset's Std: root and contact blocks / 5 (its `feat_bias`)."""
    std = np.array(std, dtype=np.float32, copy=True)
    j = num_joints or skeleton_for_dim(std.shape[-1]).num_joints
    for name, sl in feature_slices(j).items():
        if name in _ROOT_AND_CONTACT:
            std[..., sl] /= EVALUATOR_STD_BIAS
    return std
