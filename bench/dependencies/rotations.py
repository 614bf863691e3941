"""The project's rotation conversions against libraries: numpy (motiondiff.geometry.rotations) against scipy's
Rotation, torch (motiondiff.geometry.torch_rotations) against roma.

    /tmp/depvenv/bin/python bench/dependencies/rotations.py [--n 100000]

Same inputs for both: n random rotations (uniform quaternions, seeded), as quaternions, matrices, axis-angle
vectors, 6D and intrinsic Euler angles. Faithfulness: max |difference| of the outputs (quaternions compared up to
sign). Speed: the fastest of 7 interleaved runs each, in this process, one thread (numpy float64; torch float32,
forward only and forward + backward). Gradients: where each torch function is singular (zero rotation, half turns), the share of non-finite
input gradients of sum(output); elsewhere max |difference| of the two libraries' gradients. Conventions: the project
stores quaternions as (w, x, y, z), roma and scipy as (x, y, z, w): the reorder is left out of the library's time
(replacing would move the whole project to (x, y, z, w) or pay it at every call). Writes
docs/results/dependencies/rotations.json.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import torch
from scipy.spatial.transform import Rotation

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import import_seconds, install_cost, max_abs, require, speed, write  # noqa: E402

import motiondiff.geometry.rotations as R  # noqa: E402
import motiondiff.geometry.torch_rotations as T  # noqa: E402

roma = require("roma")

XYZW, WXYZ = [1, 2, 3, 0], [3, 0, 1, 2]


def _signless(a, b) -> float:
    """max |a - b| of quaternions up to sign (q and -q are one rotation)."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    b = np.where((a * b).sum(-1, keepdims=True) < 0, -b, b)
    return float(np.abs(a - b).max())


def inputs(n: int, seed: int = 0) -> dict:
    rng = np.random.default_rng(seed)
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    q2 = rng.normal(size=(n, 4))
    q2 /= np.linalg.norm(q2, axis=-1, keepdims=True)
    m = R.quat_to_matrix(q)
    return {"q": q, "q2": q2, "m": m, "v": rng.normal(size=(n, 3)), "rotvec": R.quat_to_rotvec(q),
            "d6": R.matrix_to_6d(m) + 0.05 * rng.normal(size=(n, 6)), "euler": rng.uniform(-np.pi, np.pi, (n, 3)),
            "t": rng.uniform(0, 1, n), "src": rng.normal(size=(2000, 5, 3))}  # fmt: skip


# ---- numpy against scipy ------------------------------------------------------------------------------------------
def numpy_pairs(x: dict) -> dict:
    """name -> (project fn, scipy fn, comparison); scipy works in (x, y, z, w), and its side includes building the
    Rotation from the project's arrays (what a call site would do)."""
    q, q2, v, t = x["q"], x["q2"], x["v"], x["t"]

    def scipy_slerp():
        r0, r1 = Rotation.from_quat(q[:, XYZW]), Rotation.from_quat(q2[:, XYZW])
        return (r0 * Rotation.from_rotvec((r0.inv() * r1).as_rotvec() * t[:, None])).as_quat()[:, WXYZ]

    tgt = np.einsum("nij,nkj->nki", R.quat_to_matrix(q[:2000]), x["src"])  # rotated copies: kabsch is exact

    def scipy_kabsch():
        return np.stack([Rotation.align_vectors(tgt[i], x["src"][i])[0].as_matrix() for i in range(len(tgt))])

    few_q, few_v = q[:200], v[:200]  # one joint of a 10 s clip at 20 fps: what forward kinematics rotates per call
    return {
        "qmul (Hamilton product)": (lambda: R.qmul(q, q2), lambda: (Rotation.from_quat(q[:, XYZW]) * Rotation.from_quat(q2[:, XYZW])).as_quat()[:, WXYZ], _signless),
        "qrot on 200 rotations, quaternion in (w, x, y, z) (one FK call)": (
            lambda: R.qrot(few_q, few_v), lambda: Rotation.from_quat(few_q[:, XYZW]).apply(few_v), max_abs),
        "qrot (rotate vectors)": (lambda: R.qrot(q, v), lambda: Rotation.from_quat(q[:, XYZW]).apply(v), max_abs),
        "quat_to_matrix": (lambda: R.quat_to_matrix(q), lambda: Rotation.from_quat(q[:, XYZW]).as_matrix(), max_abs),
        "qinv": (lambda: R.qinv(q), lambda: Rotation.from_quat(q[:, XYZW]).inv().as_quat()[:, WXYZ], _signless),
        "qslerp (pairwise, per-pair t)": (lambda: R.qslerp(q, q2, t), scipy_slerp, _signless),
        "kabsch (2000 fits of 5 vectors; scipy: one call per fit)": (
            lambda: R.kabsch(x["src"], tgt), scipy_kabsch, max_abs),
    }  # fmt: skip


def numpy_section(x: dict) -> dict:
    out = {}
    for name, (ours, theirs, compare) in numpy_pairs(x).items():
        out[name] = {"max_abs_difference": compare(ours(), theirs()), **speed(ours, theirs)}
    return out


# ---- torch against roma -------------------------------------------------------------------------------------------
def torch_pairs(x: dict, dtype=torch.float32) -> dict:
    """name -> (project fn, roma fn, inputs in the project's layout, in roma's, output comparison, input kinds);
    a kind is "q" (a unit quaternion), "d6" (6D: project (..., 6), roma (..., 3, 2)) or "plain"."""

    def tt(a):
        return torch.as_tensor(np.ascontiguousarray(a), dtype=dtype)

    q, q2, m, v, rv, d6, eu = (tt(x[k]) for k in ("q", "q2", "m", "v", "rotvec", "d6", "euler"))
    qx, q2x = q[:, XYZW].contiguous(), q2[:, XYZW].contiguous()
    d6_cols = d6.reshape(-1, 2, 3).transpose(-1, -2).contiguous()  # (R00, R10, R20, R01, R11, R21) -> (3, 2)

    def quat_out(a, b):
        return _signless(a.detach().numpy(), b.detach().numpy()[:, WXYZ])

    return {
        "qmul": (T.qmul, roma.quat_product, (q, q2), (qx, q2x), quat_out, ("q", "q")),
        "qrot": (T.qrot, roma.quat_action, (q, v), (qx, v), max_abs, ("q", "plain")),
        "quat_to_matrix": (T.quat_to_matrix, roma.unitquat_to_rotmat, (q,), (qx,), max_abs, ("q",)),
        "matrix_to_quat": (T.matrix_to_quat, roma.rotmat_to_unitquat, (m,), (m,), quat_out, ("plain",)),
        "sixd_to_matrix (Gram-Schmidt)": (T.sixd_to_matrix, roma.special_gramschmidt, (d6,), (d6_cols,), max_abs,
                                          ("d6",)),
        "axis_angle_to_matrix": (T.axis_angle_to_matrix, roma.rotvec_to_rotmat, (rv,), (rv,), max_abs, ("plain",)),
        "axis_angle_to_quat": (T.axis_angle_to_quat, roma.rotvec_to_unitquat, (rv,), (rv,), quat_out, ("plain",)),
        "quat_to_axis_angle": (T.quat_to_axis_angle, roma.unitquat_to_rotvec, (q,), (qx,), max_abs, ("q",)),
        "matrix_to_axis_angle": (T.matrix_to_axis_angle, roma.rotmat_to_rotvec, (m,), (m,), max_abs, ("plain",)),
        "euler_to_matrix (intrinsic ZXY)": (lambda a: T.euler_to_matrix(a, "ZXY"),
                                            lambda a: roma.euler_to_rotmat("ZXY", a), (eu,), (eu,), max_abs,
                                            ("plain",)),
    }  # fmt: skip


def _grad(fn, args):
    args = [a.detach().clone().requires_grad_(True) for a in args]
    grads = torch.autograd.grad(fn(*args).sum(), args, allow_unused=True)
    return [g if g is not None else torch.zeros_like(a) for g, a in zip(grads, args, strict=True)]


def _as_project(grad: torch.Tensor, kind: str) -> torch.Tensor:
    """roma's input gradient in the project's layout; for quaternions, both sides keep the tangent part only (the
    functions agree on unit quaternions; off them one normalises and the other does not)."""
    if kind == "d6":
        return grad.transpose(-1, -2).reshape(grad.shape[0], 6)
    if kind == "q":
        grad = grad[:, WXYZ]
    return grad


def _tangent(grad: torch.Tensor, q: torch.Tensor) -> torch.Tensor:
    return grad - (grad * q).sum(-1, keepdim=True) * q


def singular_inputs(dtype=torch.float64) -> dict:
    """Inputs where a conversion divides by zero unless written with care: the zero rotation and half turns."""
    turns = torch.tensor(np.concatenate([np.eye(3), -np.eye(3), [[0.6, 0.8, 0.0]]]), dtype=dtype)
    half_m = T.axis_angle_to_matrix(np.pi * turns)
    zero_v = torch.zeros(8, 3, dtype=dtype)
    ident_q = torch.tensor([[1.0, 0, 0, 0]], dtype=dtype).repeat(8, 1)
    return {
        "axis_angle_to_matrix": ((zero_v,), (zero_v,)),
        "axis_angle_to_quat": ((zero_v,), (zero_v,)),
        "quat_to_axis_angle": ((ident_q,), (ident_q[:, XYZW],)),
        "matrix_to_axis_angle": ((half_m,), (half_m,)),
        "matrix_to_quat": ((half_m,), (half_m,)),
    }


def _nonfinite_share(grads) -> float:
    return float(np.mean([(~torch.isfinite(g)).reshape(g.shape[0], -1).any(-1).double().mean().item() for g in grads]))


def torch_section(x: dict) -> dict:
    pairs32, pairs64 = torch_pairs(x, torch.float32), torch_pairs(x, torch.float64)
    sing = singular_inputs()
    out = {}
    for name, (ours, theirs, a_ours, a_theirs, compare, kinds) in pairs32.items():
        _, _, b_ours, b_theirs, _, _ = pairs64[name]
        row = {"max_abs_difference_float32": compare(ours(*a_ours), theirs(*a_theirs)),
               "max_abs_difference_float64": compare(ours(*b_ours), theirs(*b_theirs))}  # fmt: skip
        with torch.no_grad():
            row["forward"] = speed(lambda: ours(*a_ours), lambda: theirs(*a_theirs))  # noqa: B023
        row["forward_backward"] = speed(lambda: _grad(ours, a_ours), lambda: _grad(theirs, a_theirs))  # noqa: B023
        if compare is max_abs:  # same output (not just the same rotation up to sign): the same derivative
            g_ours, g_theirs = _grad(ours, b_ours), _grad(theirs, b_theirs)
            diffs = []
            for go, gt, kind, inp in zip(g_ours, g_theirs, kinds, b_ours, strict=True):
                gt = _as_project(gt, kind)
                if kind == "q":
                    go, gt = _tangent(go, inp), _tangent(gt, inp)
                diffs.append(max_abs(go, gt))
            row["gradient_max_abs_difference_float64"] = max(diffs)
        if name.split(" ")[0] in sing:
            s_ours, s_theirs = sing[name.split(" ")[0]]
            row["singular_inputs_nonfinite_gradient_share"] = {"project": _nonfinite_share(_grad(ours, s_ours)),
                                                               "roma": _nonfinite_share(_grad(theirs, s_theirs))}  # fmt: skip
        out[name] = row
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--n", type=int, default=100_000, help="random rotations")
    args = parser.parse_args(argv)
    x = inputs(args.n)
    result = {
        "n": args.n,
        "numpy_vs_scipy": numpy_section(x),
        "torch_vs_roma": torch_section(x),
        "size": {
            "roma": install_cost("roma"),
            "roma_import_s": import_seconds("roma"),
            "project_torch_rotations_import_s": import_seconds("motiondiff.geometry.torch_rotations"),
        },  # fmt: skip
    }
    write("rotations", result)
    for section in ("numpy_vs_scipy", "torch_vs_roma"):
        for name, row in result[section].items():
            print(section, name, {k: v for k, v in row.items()})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
