"""Inverse kinematics: local joint rotations that reproduce given joint positions on a skeleton with rest offsets.

Notation: p_j (N, 3) joint positions, o_c the rest OFFSET of child c from its parent j, W_j the world rotation of
joint j (W_root = L_root) and L_j = W_parent^-1 W_j its local rotation, so that forward kinematics is
p_c = p_j + W_j o_c. For every joint j (parents first), the observed child bones in j's parent frame are
d_c = W_parent^-1 (p_c - p_j), and L_j is chosen so that L_j o_c points along d_c:

- several children whose rest offsets span a plane (pelvis, chest): the weighted Kabsch rotation
  L_j = argmin_R sum_c |o_c| |R o^_c - d^_c|^2 (SVD), exact when the motion keeps the rest arrangement of the
  sibling bones (see `fit_rest_offsets` for rest offsets that do);
- one child (or collinear children): the shortest arc from o^ to d^ ("swing", no twist about the bone) times a
  twist about the bone that keeps L_j continuous in time (`_continuous_twist`);
- no child (a leaf): identity, as nothing observed constrains it.

With rest offsets of the motion's bone lengths and sibling arrangement, FK(L, offsets, root) gives back every
joint to float precision. Vectorised over frames; the loop runs over joints only.
"""

from __future__ import annotations

import numpy as np

from motiondiff.geometry.kinematics import forward_kinematics, forward_kinematics_torch
from motiondiff.geometry.rotations import (
    axis_angle_to_quat,
    kabsch,
    matrix_to_quat,
    qfix,
    qinv,
    qmul,
    qnormalize,
    qrot,
    qswing,
    qtwist_angle,
    quat_to_matrix,
)
from motiondiff.geometry.skeleton import Skeleton
from motiondiff.geometry.torch_rotations import axis_angle_to_matrix

__all__ = ["DEFAULT_TWIST_HALF_LIFE", "REFINE_ABOVE_M", "fit_rest_offsets", "fit_rotations", "refine_rotations",
           "solve_rotations"]  # fmt: skip

# Frames (1 s at 20 fps) for a twist carried through a swing singularity to fade by half. Longer: smaller steps
# (about 180 deg x (1 - 2^(-1/half_life)) per frame at worst); shorter: back to the untwisted solution sooner.
DEFAULT_TWIST_HALF_LIFE = 20.0
REFINE_ABOVE_M = 1e-3  # an IK fit worse than this (bones that change length: generated joints) is polished
_PLANAR = 1e-6  # |sin| between two rest directions above which a joint's children fix a full rotation
_TINY = 1e-12


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), _TINY)


def _spans_plane(directions: np.ndarray) -> bool:
    """Whether unit vectors (K, 3) are not all collinear, i.e. whether they fix a rotation completely."""
    return (
        len(directions) >= 2
        and float(np.linalg.norm(np.cross(directions[:, None], directions[None]), axis=-1).max()) > _PLANAR
    )


def _check_positions(positions: np.ndarray, skeleton: Skeleton, offsets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    positions = np.asarray(positions, dtype=np.float64)
    j = skeleton.num_joints
    if positions.ndim != 3 or positions.shape[1:] != (j, 3) or len(positions) == 0:
        raise ValueError(
            f"IK needs joint positions of shape (frames >= 1, {j}, 3) for skeleton {skeleton.name!r}, got "
            f"{positions.shape}; pass one clip at a time, joints in the skeleton's order"
        )
    if not np.isfinite(positions).all():
        raise ValueError("IK: joint positions contain NaN or Inf; fix or drop those frames first")
    offsets = np.asarray(offsets, dtype=np.float64)
    if offsets.shape != (j, 3) or not np.isfinite(offsets).all():
        raise ValueError(f"IK: offsets must be finite with shape ({j}, 3), got {offsets.shape}")
    return positions, offsets


def solve_rotations(
    positions: np.ndarray,
    skeleton: Skeleton,
    offsets: np.ndarray | None = None,
    *,
    twist_half_life: float = DEFAULT_TWIST_HALF_LIFE,
) -> tuple[np.ndarray, np.ndarray]:
    """Joint positions (N, J, 3) -> local rotations (N, J, 4) (w, x, y, z; the root's is global, sign-continuous
    over time) and root positions (N, 3), on `skeleton` with rest `offsets` (default: the skeleton's).

    `twist_half_life` (frames, > 0): a twist carried through a swing singularity returns to the untwisted solution
    with this half-life (see `_continuous_twist`)."""
    offsets = skeleton.offsets if offsets is None else offsets
    positions, offsets = _check_positions(positions, skeleton, offsets)
    if not twist_half_life > 0:
        raise ValueError(f"twist_half_life must be a positive number of frames, got {twist_half_life}")
    frames, joints = positions.shape[:2]
    identity = np.broadcast_to(np.array([1.0, 0.0, 0.0, 0.0]), (frames, 4))
    local = np.empty((frames, joints, 4))
    world = np.empty((frames, joints, 4))
    for j, p in enumerate(skeleton.parents):
        parent_world = identity if p < 0 else world[:, p]
        kids = [c for c in skeleton.children[j] if np.linalg.norm(offsets[c]) > _TINY]
        if not kids:
            rot = identity.copy()
        else:
            observed = qrot(qinv(parent_world)[:, None], positions[:, kids] - positions[:, [j]])  # (N, K, 3)
            rot = _fit_joint(offsets[kids], observed, twist_half_life)
        local[:, j] = qfix(rot)
        world[:, j] = qmul(parent_world, local[:, j])
    return local, positions[:, 0].copy()


def _fit_joint(rest: np.ndarray, observed: np.ndarray, twist_half_life: float) -> np.ndarray:
    """Local rotation (N, 4) taking the rest child offsets (K, 3) onto the observed child bones (N, K, 3)."""
    lengths = np.linalg.norm(rest, axis=-1)
    rest_dir, seen_dir = _unit(rest), _unit(observed)
    if _spans_plane(rest_dir):
        return qnormalize(matrix_to_quat(kabsch(rest_dir, seen_dir, lengths)))
    # Collinear children (usually one): the heaviest child's direction; opposite ones count with their sign.
    axis = rest_dir[np.argmax(lengths)]
    target = (seen_dir * (lengths * (rest_dir @ axis))[:, None]).sum(axis=1)
    still = np.linalg.norm(target, axis=-1) < _TINY  # a zero-length observed bone: no evidence, keep the rest pose
    target = np.where(still[:, None], axis, target)
    swing = qswing(np.broadcast_to(axis, target.shape), target)
    return qmul(swing, _continuous_twist(swing, axis, twist_half_life))


def _continuous_twist(swing: np.ndarray, axis: np.ndarray, half_life: float) -> np.ndarray:
    """Twist quaternions T(alpha_t) about `axis` that make swing_t T(alpha_t) continuous in t.

    The swing S_t (shortest arc from the rest direction u) is smooth except where the bone nears -u: there its arc
    axis spins and S_t turns fast about the bone (a flip at -u itself). Split S_{t-1}^-1 S_t = G_t T(beta_t)
    (swing G_t, twist beta_t about u) and set alpha_t = lam alpha_{t-1} - beta_t, lam = 2^(-1/half_life). Then
    L_{t-1}^-1 L_t = T(-alpha_{t-1}) G_t T(lam alpha_{t-1}), whose angle is at most the bone's own turn between the
    frames plus (1 - lam)|alpha_{t-1}|: the twist is carried through the singularity and then fades back to the
    untwisted solution, so long motions do not drift. A linear recurrence, so lfilter runs it vectorised."""
    beta = np.zeros(len(swing))
    if len(swing) > 1:
        beta[1:] = qtwist_angle(qmul(qinv(swing[:-1]), swing[1:]), axis)
    lam = 0.5 ** (1.0 / half_life)
    from scipy.signal import lfilter  # here: scipy.signal takes about a second to import, and only this needs it

    alpha = lfilter([1.0], [1.0, -lam], -beta)
    return axis_angle_to_quat(np.broadcast_to(axis, swing[..., 1:].shape), alpha)


def fit_rest_offsets(positions: np.ndarray, skeleton: Skeleton) -> np.ndarray:
    """Rest offsets (J, 3) under which `solve_rotations` reproduces the motion: each bone gets its median length over
    the frames along the skeleton's rest direction (+y where the skeleton's offset is zero); the children of a
    branching joint (pelvis, chest) get instead their arrangement in the motion - the Procrustes mean of the sibling
    bones over the frames - turned by the best-fit rotation onto the skeleton's rest arrangement, so the rest pose
    still looks like the skeleton's while the arrangement matches the data (a single rotation per joint can only
    place several children exactly when their arrangement is the rest one)."""
    positions, _ = _check_positions(positions, skeleton, skeleton.offsets)
    parents = np.array(skeleton.parents)
    offsets = np.zeros((skeleton.num_joints, 3))
    bones = positions[:, 1:] - positions[:, parents[1:]]
    lengths = np.median(np.linalg.norm(bones, axis=-1), axis=0)
    rest_dir = _unit(np.asarray(skeleton.offsets, dtype=np.float64)[1:])
    rest_dir[np.linalg.norm(rest_dir, axis=-1) < 0.5] = [0.0, 1.0, 0.0]
    offsets[1:] = rest_dir * lengths[:, None]
    for j, kids in enumerate(skeleton.children):
        kids = [c for c in kids if np.linalg.norm(offsets[c]) > _TINY]
        if _spans_plane(_unit(offsets[kids])):
            offsets[kids] = _sibling_arrangement(positions[:, kids] - positions[:, [j]], offsets[kids])
    return offsets


def _sibling_arrangement(bones: np.ndarray, template: np.ndarray, iterations: int = 3) -> np.ndarray:
    """Generalised Procrustes: the shape M (K, 3) minimising sum_t |R_t M - X_t|^2 over rotations R_t, for sibling
    bones X_t (N, K, 3), oriented like `template`. For a rigid arrangement (X_t = Q_t S) one step is exact:
    R_t = Q_t A for a fixed A, so the mean of R_t^T X_t is A^T S, S turned rigidly."""
    shape = template
    for _ in range(iterations):
        pose = kabsch(np.broadcast_to(shape, bones.shape), bones)  # (N, 3, 3)
        shape = np.einsum("nji,nkj->ki", pose, bones) / len(bones)  # mean of R_t^T x_tk
    return shape @ kabsch(shape, template).T


def refine_rotations(
    positions: np.ndarray,
    skeleton: Skeleton,
    offsets: np.ndarray,
    rotations: np.ndarray,
    root: np.ndarray,
    *,
    powers: tuple[float, ...] = (2.0, 8.0, 32.0),
    iterations: int = 60,
) -> tuple[np.ndarray, np.ndarray]:
    """Polish `solve_rotations`'s answer for joints whose bones are not rigid: local rotations (N, J, 4) and one
    length per bone (offsets (J, 3), directions kept) that bring forward kinematics close to `positions` at every
    frame and joint (torch L-BFGS from the IK solution; the root stays at `root`).

    Direction matching is exact for rigid bones, but generated joints change bone lengths from frame to frame and
    bend the pelvis and chest arrangement (measurements: docs/editing.md), and it passes each such error whole to
    every joint below (a misplaced collar moves the whole arm). The fit spreads it over the chain instead, minimising the
    mean of d^p over frames and joints (d: distance) for each p in `powers` in turn: least squares first, then
    higher powers, which approach the smallest worst-case distance. Returns (rotations, offsets)."""
    import torch

    positions, offsets = _check_positions(positions, skeleton, offsets)
    target = torch.as_tensor(positions)
    base = torch.as_tensor(quat_to_matrix(np.asarray(rotations, dtype=np.float64)))
    rest = torch.as_tensor(offsets[1:])
    top = torch.as_tensor(np.asarray(root, dtype=np.float64))[:, None]
    turn = torch.zeros(base.shape[:2] + (3,), dtype=torch.float64, requires_grad=True)  # axis-angle change per joint
    stretch = torch.zeros(len(rest), dtype=torch.float64, requires_grad=True)  # log length factor per bone

    def fk():
        bones = (rest * torch.exp(stretch)[:, None]).expand(len(target), -1, -1)
        local = base @ axis_angle_to_matrix(turn)
        return forward_kinematics_torch(local, torch.cat([top, bones], dim=1), skeleton.parents)[0], local

    def distance():
        return torch.sqrt(((fk()[0] - target) ** 2).sum(-1) + 1e-18)

    for power in powers:
        with torch.no_grad():
            scale = float(distance().max()) + 1e-9  # distances in units of the current worst: well scaled
        optimizer = torch.optim.LBFGS([turn, stretch], max_iter=iterations, history_size=20,
                                      line_search_fn="strong_wolfe", tolerance_grad=1e-12, tolerance_change=1e-15)  # fmt: skip

        def closure(power=power, scale=scale, optimizer=optimizer):
            optimizer.zero_grad()
            loss = ((distance() / scale) ** power).mean()
            loss.backward()
            return loss

        optimizer.step(closure)
    with torch.no_grad():
        local = fk()[1].numpy()
        lengths = np.exp(stretch.numpy())
    out = offsets.copy()
    out[1:] *= lengths[:, None]
    return qfix(qnormalize(matrix_to_quat(local))), out


def fit_rotations(
    positions: np.ndarray,
    skeleton: Skeleton,
    offsets: np.ndarray,
    *,
    twist_half_life: float = DEFAULT_TWIST_HALF_LIFE,
    refine_above: float = REFINE_ABOVE_M,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(rotations, root, offsets) reproducing `positions` on `skeleton`: `solve_rotations`, exact for rigid bones,
    then `refine_rotations` (rotations and bone lengths) where some joint is more than `refine_above` metres off."""

    rotations, root = solve_rotations(positions, skeleton, offsets, twist_half_life=twist_half_life)
    translations = np.repeat(np.asarray(offsets, dtype=np.float64)[None], len(rotations), axis=0)
    translations[:, 0] = root
    error = np.linalg.norm(forward_kinematics(rotations, translations, skeleton.parents)[0] - positions, axis=-1)
    if error.max() > refine_above:
        rotations, offsets = refine_rotations(positions, skeleton, offsets, rotations, root)
    return rotations, root, offsets
