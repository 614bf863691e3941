"""Differentiable rotation conversions in torch (any leading batch shape, the input's dtype and device).

Same conventions as motiondiff.geometry.rotations (the numpy twin used for encoding): quaternions (w, x, y, z), matrices act
on column vectors, 6D = first two matrix columns (R00, R10, R20, R01, R11, R21), intrinsic Euler angles where the
order "XYZ" means R = Rx(a0) @ Ry(a1) @ Rz(a2) - but angles here are in RADIANS (losses and decoders want them).

Every function keeps gradients finite at the usual singular points (zero rotation, 180-degree turns): branches are
selected with torch.where on safe arguments so the untaken branch never produces NaN gradients.
"""

from __future__ import annotations

import torch

from motiondiff.geometry.quaternion_algebra import hamilton, matrix_entries

_EPS = 1e-12


def _safe_sqrt(x: torch.Tensor) -> torch.Tensor:
    """sqrt(max(x, 0)) with a zero (not infinite) gradient at 0."""
    positive = x > 0
    return torch.where(positive, torch.sqrt(torch.where(positive, x, torch.ones_like(x))), torch.zeros_like(x))


def _norm(v: torch.Tensor, keepdim: bool = False) -> torch.Tensor:
    return _safe_sqrt((v * v).sum(-1, keepdim=keepdim))


# ---- quaternions ------------------------------------------------------------------------------------------------
def qnormalize(q: torch.Tensor) -> torch.Tensor:
    return q / _norm(q, keepdim=True).clamp_min(_EPS)


def qmul(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """Hamilton product a * b (apply b first, then a)."""
    return torch.stack(hamilton(a.unbind(-1), b.unbind(-1)), dim=-1)


def qinv(q: torch.Tensor) -> torch.Tensor:
    """Inverse of a unit quaternion (its conjugate)."""
    return q * q.new_tensor([1.0, -1.0, -1.0, -1.0])


def qrot(q: torch.Tensor, v: torch.Tensor) -> torch.Tensor:
    """Rotate vectors v (..., 3) by unit quaternions q (..., 4); q and v broadcast."""
    shape = torch.broadcast_shapes(q.shape[:-1], v.shape[:-1])  # cross products need equal shapes
    q, v = q.expand(shape + (4,)), v.expand(shape + (3,))
    u = q[..., 1:]
    uv = torch.linalg.cross(u, v)
    return v + 2.0 * (q[..., :1] * uv + torch.linalg.cross(u, uv))


def quat_to_matrix(q: torch.Tensor) -> torch.Tensor:
    return torch.stack(matrix_entries(qnormalize(q).unbind(-1)), dim=-1).reshape(q.shape[:-1] + (3, 3))


def matrix_to_quat(m: torch.Tensor) -> torch.Tensor:
    """Rotation matrices -> unit quaternions with w >= 0. Of the four textbook formulas (each divides by one of
    4w^2, 4x^2, 4y^2, 4z^2) the best-conditioned one is taken per rotation, so 180-degree turns stay exact."""
    m00, m01, m02, m10, m11, m12, m20, m21, m22 = m.reshape(m.shape[:-2] + (9,)).unbind(-1)
    q_abs = _safe_sqrt(
        torch.stack(
            [1 + m00 + m11 + m22, 1 + m00 - m11 - m22, 1 - m00 + m11 - m22, 1 - m00 - m11 + m22],
            dim=-1,
        )
    )  # (2|w|, 2|x|, 2|y|, 2|z|)
    candidates = torch.stack(
        [
            torch.stack([q_abs[..., 0] ** 2, m21 - m12, m02 - m20, m10 - m01], dim=-1),
            torch.stack([m21 - m12, q_abs[..., 1] ** 2, m10 + m01, m02 + m20], dim=-1),
            torch.stack([m02 - m20, m10 + m01, q_abs[..., 2] ** 2, m12 + m21], dim=-1),
            torch.stack([m10 - m01, m20 + m02, m21 + m12, q_abs[..., 3] ** 2], dim=-1),
        ],
        dim=-2,
    ) / (2.0 * q_abs[..., None].clamp_min(0.1))
    pick = torch.nn.functional.one_hot(q_abs.argmax(-1), 4).to(m.dtype)
    q = (candidates * pick[..., None]).sum(-2)
    q = torch.where(q[..., :1] < 0, -q, q)  # one sign convention (w >= 0), like scipy
    return qnormalize(q)


# ---- 6D (Zhou et al. 2019) --------------------------------------------------------------------------------------
def matrix_to_6d(m: torch.Tensor) -> torch.Tensor:
    return torch.cat([m[..., :, 0], m[..., :, 1]], dim=-1)


def sixd_to_matrix(d6: torch.Tensor) -> torch.Tensor:
    """Gram-Schmidt on the two stored columns; the third column is their cross product (det +1)."""
    a1, a2 = d6[..., :3], d6[..., 3:]
    b1 = a1 / _norm(a1, keepdim=True).clamp_min(_EPS)
    b2 = a2 - (b1 * a2).sum(-1, keepdim=True) * b1
    b2 = b2 / _norm(b2, keepdim=True).clamp_min(_EPS)
    b3 = torch.linalg.cross(b1, b2)
    return torch.stack([b1, b2, b3], dim=-1)


# ---- axis-angle -------------------------------------------------------------------------------------------------
def axis_angle_to_matrix(v: torch.Tensor) -> torch.Tensor:
    """Rodrigues: R = I + a K + b K^2 with a = sin(t)/t, b = (1-cos t)/t^2 (Taylor series near t = 0)."""
    t2 = (v * v).sum(-1)
    small = t2 < 1e-6
    t2_safe = torch.where(small, torch.ones_like(t2), t2)
    t = torch.sqrt(t2_safe)
    a = torch.where(small, 1 - t2 / 6 + t2 * t2 / 120, torch.sin(t) / t)
    b = torch.where(small, 0.5 - t2 / 24 + t2 * t2 / 720, (1 - torch.cos(t)) / t2_safe)
    x, y, z = v.unbind(-1)
    zero = torch.zeros_like(x)
    k = torch.stack([zero, -z, y, z, zero, -x, -y, x, zero], dim=-1).reshape(v.shape[:-1] + (3, 3))
    eye = torch.eye(3, dtype=v.dtype, device=v.device)
    return eye + a[..., None, None] * k + b[..., None, None] * (k @ k)


def quat_to_axis_angle(q: torch.Tensor) -> torch.Tensor:
    """Unit quaternions -> rotation vectors with angle in [0, pi] (q and -q give the same vector)."""
    q = qnormalize(q)
    q = torch.where(q[..., :1] < 0, -q, q)
    s = _norm(q[..., 1:])
    angle = 2 * torch.atan2(s, q[..., 0])
    small = s < 1e-6
    # angle / sin(angle/2) -> 2 + angle^2 / 12 as the angle goes to 0
    factor = torch.where(small, 2 + angle * angle / 12, angle / torch.where(small, torch.ones_like(s), s))
    return q[..., 1:] * factor[..., None]


def matrix_to_axis_angle(m: torch.Tensor) -> torch.Tensor:
    return quat_to_axis_angle(matrix_to_quat(m))


def axis_angle_to_quat(v: torch.Tensor) -> torch.Tensor:
    t2 = (v * v).sum(-1, keepdim=True)
    small = t2 < 1e-6
    t = torch.sqrt(torch.where(small, torch.ones_like(t2), t2))
    half_sinc = torch.where(small, 0.5 - t2 / 48, torch.sin(t / 2) / t)  # sin(t/2)/t
    w = torch.where(small, 1 - t2 / 8, torch.cos(t / 2))
    return torch.cat([w, v * half_sinc], dim=-1)


# ---- Euler (radians) --------------------------------------------------------------------------------------------
def _axis_matrix(axis: str, angle: torch.Tensor) -> torch.Tensor:
    c, s = torch.cos(angle), torch.sin(angle)
    one, zero = torch.ones_like(angle), torch.zeros_like(angle)
    rows = {
        "X": (one, zero, zero, zero, c, -s, zero, s, c),
        "Y": (c, zero, s, zero, one, zero, -s, zero, c),
        "Z": (c, -s, zero, s, c, zero, zero, zero, one),
    }[axis]
    return torch.stack(rows, dim=-1).reshape(angle.shape + (3, 3))


def euler_to_matrix(angles: torch.Tensor, order: str) -> torch.Tensor:
    """Intrinsic Euler angles (..., 3) in RADIANS -> matrices: order "XYZ" is Rx(a0) @ Ry(a1) @ Rz(a2)."""
    order = order.upper()
    if len(order) != 3 or set(order) - set("XYZ"):
        raise ValueError(f"Euler order must be three of X, Y, Z (e.g. 'XYZ'), got {order!r}")
    a0, a1, a2 = angles.unbind(-1)
    return _axis_matrix(order[0], a0) @ _axis_matrix(order[1], a1) @ _axis_matrix(order[2], a2)
