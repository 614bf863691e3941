"""Close the root path of an in-betweened HumanML3D motion so the kept frames after a gap land where the input had them.

HumanML3D features (hml263 / kit251) store the root as per-row velocities: row i holds ω_i, the half-angle turn about
y from frame i to i+1, and v_i, the x/z step from frame i to i+1 expressed in frame i+1's facing frame. Decoding
integrates them (``recover_root``):

    h_k = Σ_{i<k} ω_i                         heading of frame k (quaternion q(h) = (cos h, 0, sin h, 0))
    p_k = Σ_{i<k} q(h_{i+1})⁻¹ · v_i          root x/z of frame k (the step rotated back to the world)

In-painting keeps the input's rows outside a gap G = [a, b) exactly, but the generated rows of G integrate to their
own turn and displacement, so every frame after the gap is rotated and shifted against the input. The residuals are
spread evenly over the gap, first the turn, then (with the corrected headings) the displacement:

    ω_i ← ω_i + (Σ_G ω^in − Σ_G ω) / |G|
    v_i ← q(h_{i+1}) · (q(h_{i+1})⁻¹ · v_i + (Σ_G w^in − Σ_G w) / |G|)     w_i = q(h_{i+1})⁻¹ · v_i, world steps

after which h_b and p_b equal the input's, and so does every decoded frame from b on (root height and the
root-relative rows are stored absolutely). Rig representations store the root position itself: nothing to close.
"""

from __future__ import annotations

import numpy as np

from motiondiff.data.representations import HMLRepresentation, Representation
from motiondiff.geometry.rotations import qinv, qrot

TURN, STEP = 0, slice(1, 3)  # dims of ω and of the x/z velocity in a HumanML3D row


def needs_root_closure(representation: Representation) -> bool:
    """True for layouts that store the root as velocities (HumanML3D features)."""
    return isinstance(representation, HMLRepresentation)


def _yaw(half_angle: np.ndarray) -> np.ndarray:
    zero = np.zeros_like(half_angle)
    return np.stack([np.cos(half_angle), zero, np.sin(half_angle), zero], axis=-1)


def headings(features: np.ndarray) -> np.ndarray:
    """(N + 1,) half-angle headings h_0 .. h_N of the frames the N rows lead to (h_0 = 0)."""
    return np.concatenate([[0.0], np.cumsum(features[:, TURN], dtype=np.float64)])


def world_steps(features: np.ndarray, h: np.ndarray) -> np.ndarray:
    """(N, 3) world x/z steps w_i = q(h_{i+1})⁻¹ · v_i of every row (y = 0)."""
    v = np.zeros((len(features), 3))
    v[:, [0, 2]] = features[:, STEP]
    return qrot(qinv(_yaw(h[1:])), v)


def gaps(generated: np.ndarray) -> list[tuple[int, int]]:
    """[start, stop) of every run of True in a (N,) bool mask."""
    edges = np.diff(np.concatenate([[0], generated.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(edges == 1).tolist(), np.flatnonzero(edges == -1).tolist(), strict=True))


def close_root_path(features: np.ndarray, known: np.ndarray, generated: np.ndarray) -> np.ndarray:
    """HumanML3D rows (N, D) whose root turn and step are corrected over each generated gap (rows where
    ``generated``, (N,) bool) so the frames after the gap decode to the input's (``known``, (N, D)) world placement.
    Gaps that run to the end have nothing after them to meet and stay as generated. Returns a new array."""
    out = np.asarray(features, dtype=np.float64).copy()
    known = np.asarray(known, dtype=np.float64)
    generated = np.asarray(generated, dtype=bool)
    if out.shape != known.shape or generated.shape != out.shape[:1]:
        raise ValueError(
            f"close_root_path: features {out.shape}, known {known.shape} and generated {generated.shape} disagree"
        )
    h_in = headings(known)
    w_in = world_steps(known, h_in)
    for a, b in gaps(generated):
        if b >= len(out):
            continue
        out[a:b, TURN] += (known[a:b, TURN].sum() - out[a:b, TURN].sum()) / (b - a)
        h = headings(out)
        w = world_steps(out[a:b], h[a : b + 1])
        w += (w_in[a:b].sum(0) - w.sum(0)) / (b - a)
        out[a:b, STEP] = qrot(_yaw(h[a + 1 : b + 1]), w)[:, [0, 2]]
    return out.astype(np.asarray(features).dtype)
