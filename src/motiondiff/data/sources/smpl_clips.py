"""SMPL sequences (axis-angle poses + joint positions) -> `ClipMotion`s on the SMPL-24 rig, shared by the
HumanAct12 and UESTC loaders.

The pickles hold SMPL pose parameters but not the body model, so the rest skeleton (bone offsets) of each clip is
recovered from its joint positions and the world rotations the poses give: with every joint's world rotation known,
each observed joint is a linear function of the offsets on the path from its nearest observed ancestor,
    p_j - p_a = sum_k R_world(parent(k)) @ offset_k,
solved by least squares over all frames. When every joint is observed (HumanAct12) this is exactly
offset_j = mean_t R_parent(t)^-1 (p_j(t) - p_parent(t)); offsets no joint constrains (UESTC's feet, head, hands)
keep the SMPL-neutral template, scaled to the clip's measured bones.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from motiondiff.data.representations.clip import ClipMotion
from motiondiff.data.representations.hml_features import canonicalize_joints, ground_and_face
from motiondiff.geometry.kinematics import forward_kinematics
from motiondiff.geometry.rotations import qmul, qrot, quat_to_matrix
from motiondiff.geometry.skeleton import SMPL22, SMPL24

PELVIS, NECK = 0, 12
# Rotation taking each possible source up axis to +y (proper rotations: left and right are never swapped).
_AXES = {"+x": (1, 0, 0), "-x": (-1, 0, 0), "+y": (0, 1, 0), "-y": (0, -1, 0), "+z": (0, 0, 1), "-z": (0, 0, -1)}
UP_TO_Y = {
    "+y": np.array([1.0, 0.0, 0.0, 0.0]),
    "-y": np.array([0.0, 1.0, 0.0, 0.0]),  # 180 deg about x: (x, y, z) -> (x, -y, -z)
    "+z": np.array([np.sqrt(0.5), -np.sqrt(0.5), 0.0, 0.0]),  # -90 deg about x
    "-z": np.array([np.sqrt(0.5), np.sqrt(0.5), 0.0, 0.0]),
    "+x": np.array([np.sqrt(0.5), 0.0, 0.0, np.sqrt(0.5)]),  # +90 deg about z
    "-x": np.array([np.sqrt(0.5), 0.0, 0.0, -np.sqrt(0.5)]),
}
LSTSQ_RCOND = 1e-4  # directions the frames barely constrain (relative eigenvalue below this) stay at the template


def action_caption(name: str) -> str:
    """The GENERATED caption of an action label (the datasets have no text)."""
    return f"a person performs {name.replace('_', ' ').strip()}."


def detect_up_axis(torso: Iterable[np.ndarray]) -> str:
    """The source axis ('+y', '-y', '+z', ...) the pelvis->neck vectors (arrays (N, 3), all clips of a file) point
    along on average. People in these datasets stand or sit upright, so over a whole file this is the up axis;
    deciding once per file keeps every clip in the same frame."""
    total = np.zeros(3)
    for v in torso:  # summed clip by clip: a whole UESTC file does not fit in memory at once as float64
        total += (v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-9)).sum(axis=0)
    if not total.any():
        return "+y"
    mean = total
    axis = int(np.abs(mean).argmax())
    return ("+" if mean[axis] > 0 else "-") + "xyz"[axis]


def axis_angle_to_quat(poses: np.ndarray) -> np.ndarray:
    """(..., 3) axis-angle (SMPL's pose parameters) -> (..., 4) quaternions (w, x, y, z)."""
    xyzw = Rotation.from_rotvec(np.asarray(poses, dtype=np.float64).reshape(-1, 3)).as_quat()
    return xyzw[:, [3, 0, 1, 2]].reshape(poses.shape[:-1] + (4,))


def world_rotations(local: np.ndarray, parents=SMPL24.parents) -> np.ndarray:
    zeros = np.zeros(local.shape[:-1] + (3,))
    return forward_kinematics(local, zeros, parents)[1]


def recover_offsets(
    world: np.ndarray, positions: np.ndarray, observed, prior: np.ndarray = SMPL24.offsets, parents=SMPL24.parents
) -> np.ndarray:
    """(J, 3) bone offsets that best reproduce `positions[:, observed]` (N, J, 3) given world rotations (N, J, 4).

    The root must be observed. Offsets the data leaves undetermined stay at `prior`, scaled by the clip's size."""
    n, j = world.shape[:2]
    obs = sorted(int(i) for i in observed)
    if PELVIS not in obs:
        raise ValueError("recover_offsets: the root joint must be observed")
    mats = quat_to_matrix(world)  # (N, J, 3, 3)
    ata = np.zeros((j, j, 3, 3))
    atb = np.zeros((j, 3))
    direct = []
    for joint in obs[1:]:
        path, anc = [joint], parents[joint]
        while anc not in obs:
            path.append(anc)
            anc = parents[anc]
        if len(path) == 1:
            direct.append(joint)
        d = positions[:, joint] - positions[:, anc]
        for k in path:
            atb[k] += np.einsum("nji,nj->i", mats[:, parents[k]], d)
            for m in path:
                ata[k, m] += np.einsum("nji,njk->ik", mats[:, parents[k]], mats[:, parents[m]])
    ata = ata.transpose(0, 2, 1, 3).reshape(3 * j, 3 * j)
    prior = np.asarray(prior, dtype=np.float64)
    free = np.abs(ata).reshape(j, 3, j * 3).sum(axis=(1, 2)) == 0  # offsets no observation involves
    measured = [k for k in direct if np.linalg.norm(prior[k]) > 1e-6]
    if measured:  # size of this body relative to the template, from the bones measured directly
        base = prior.copy()
        fit = np.linalg.lstsq(ata, atb.reshape(-1) - ata @ base.reshape(-1), rcond=LSTSQ_RCOND)[0]
        sizes = np.linalg.norm((base.reshape(-1) + fit).reshape(j, 3)[measured], axis=-1)
        prior = prior * float(np.median(sizes / np.linalg.norm(prior[measured], axis=-1)))
    delta = np.linalg.lstsq(ata, atb.reshape(-1) - ata @ prior.reshape(-1), rcond=LSTSQ_RCOND)[0]
    offsets = prior + delta.reshape(j, 3)
    offsets[free] = prior[free]
    offsets[PELVIS] = 0.0
    return offsets


@dataclass
class SmplSequence:
    """One clip brought to y-up, before placement: local rotations (N, 24, 4), root (N, 3), offsets (24, 3), and
    the SMPL-22 joints to canonicalise (the dataset's own where it has all 22, else FK of the rig)."""

    local: np.ndarray
    root: np.ndarray
    offsets: np.ndarray
    joints22: np.ndarray
    up: np.ndarray  # quaternion applied to the source frame


def smpl_sequence(poses: np.ndarray, positions: np.ndarray, observed, up_axis: str) -> SmplSequence:
    """poses (N, 72) axis-angle, positions (N, 24, 3) in the source frame (rows not in `observed` are ignored)."""
    up = UP_TO_Y[up_axis]
    n = len(poses)
    local = axis_angle_to_quat(np.asarray(poses, dtype=np.float64).reshape(n, 24, 3))
    local[:, 0] = qmul(np.broadcast_to(up, (n, 4)), local[:, 0])
    pos = qrot(np.broadcast_to(up, positions.shape[:-1] + (4,)), np.asarray(positions, dtype=np.float64))
    offsets = recover_offsets(world_rotations(local), pos, observed)
    root = pos[:, PELVIS]
    if len(set(int(i) for i in observed) & set(range(22))) == 22:
        joints22 = pos[:, :22]
    else:
        joints22 = rig_fk(local, root, offsets)[:, :22]
    return SmplSequence(local, root, offsets, joints22, up)


def rig_fk(local: np.ndarray, root: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    translations = np.broadcast_to(offsets, local.shape[:-1] + (3,)).copy()
    translations[:, 0] = root
    return forward_kinematics(local, translations, SMPL24.parents)[0]


def placed_motion(seq: SmplSequence, rig) -> tuple[ClipMotion, dict]:
    """The clip in canonical placement (floor y=0, frame-0 root at the x,z origin, facing +Z), for the rig and,
    with HumanML3D's own rule, the SMPL-22 joints. Also returns the rig's placement: a source point p lands at
    qrot(turn, qrot(up, p) + shift)."""
    turn, shift = ground_and_face(rig_fk(seq.local, seq.root, seq.offsets), SMPL24)
    n = len(seq.local)
    rotations = seq.local.copy()
    rotations[:, 0] = qmul(np.broadcast_to(turn, (n, 4)), rotations[:, 0])
    root = qrot(np.broadcast_to(turn, (n, 4)), seq.root + shift)
    motion = ClipMotion(
        joints=canonicalize_joints(seq.joints22, SMPL22).astype(np.float32),
        rotations=rotations.astype(np.float32),
        root=root.astype(np.float32),
        offsets=seq.offsets.astype(np.float32),
        rig=rig,
    )
    return motion, {"up": seq.up.tolist(), "turn": np.asarray(turn).tolist(), "shift": np.asarray(shift).tolist()}


def place_points(points: np.ndarray, placement: dict) -> np.ndarray:
    """Source-frame points (..., 3) -> the canonical placement of their clip's rig (for checks and overlays)."""
    up, turn = np.asarray(placement["up"]), np.asarray(placement["turn"])
    p = qrot(np.broadcast_to(up, points.shape[:-1] + (4,)), np.asarray(points, dtype=np.float64))
    return qrot(np.broadcast_to(turn, p.shape[:-1] + (4,)), p + np.asarray(placement["shift"]))


def mean_rig(offsets: list[np.ndarray]):
    """SMPL-24 with the mean offsets of (the train split's) clips; the template when there are none."""
    return SMPL24.with_offsets(np.mean(offsets, axis=0)) if offsets else SMPL24
