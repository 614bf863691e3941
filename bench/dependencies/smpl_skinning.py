"""The project's SMPL linear blend skinning (motiondiff.data.formats.smpl_params.SmplBody.vertices, numpy) against
smplx's (smplx.lbs.lbs, torch), on an SMPL-sized random body model (the real one is licence-restricted).

    /tmp/depvenv/bin/python bench/dependencies/smpl_skinning.py [--frames 64]

Model: 6890 vertices, 24 joints on SMPL's tree, 10 shape and 207 pose-corrective directions, skinning weights that
sum to 1; random poses (axis-angle, |θ| up to about 1 rad), translations and shape. Faithfulness: max |difference| of
the posed vertices and joints (metres). Speed: one call for all frames in this process (the project's numpy float64;
smplx in float32, its usual dtype, and in float64); smplx adds the translation afterwards, as its SMPL layer does.
A bench-only variant of the project's formula written as one matrix product shows how much of the gap is layout.
Writes docs/results/dependencies/smpl_skinning.json.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import torch

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import import_seconds, install_cost, max_abs, require, speed, write  # noqa: E402

from motiondiff.data.formats.smpl_params import SmplBody  # noqa: E402
from motiondiff.geometry.rotations import rotvec_to_quat  # noqa: E402
from motiondiff.geometry.skeleton import SMPL24  # noqa: E402

require("smplx")
from smplx.lbs import lbs  # noqa: E402

VERTICES, JOINTS, SHAPES = 6890, 24, 10


def random_body(seed: int = 0) -> SmplBody:
    rng = np.random.default_rng(seed)
    v = rng.normal(scale=0.3, size=(VERTICES, 3))
    regressor = np.zeros((JOINTS, VERTICES))
    for j in range(JOINTS):  # each joint the mean of 30 vertices, as SMPL's sparse regressor is
        regressor[j, rng.choice(VERTICES, 30, replace=False)] = 1 / 30
    weights = rng.dirichlet(np.full(JOINTS, 0.2), size=VERTICES)
    return SmplBody(v_template=v, shapedirs=rng.normal(scale=0.01, size=(VERTICES, 3, SHAPES)),
                    J_regressor=regressor, parents=np.array(SMPL24.parents), weights=weights,
                    faces=np.zeros((1, 3), dtype=np.int64),
                    posedirs=rng.normal(scale=0.001, size=(VERTICES, 3, 9 * (JOINTS - 1))))  # fmt: skip


def matmul_skinning(body: SmplBody, rotations: np.ndarray, trans: np.ndarray, betas: np.ndarray) -> np.ndarray:
    """The project's formula with the blend written as one BLAS product, weights (V, J) @ per-joint [R | t] (N, J,
    12), instead of einsums over (N, V, 3, 3): bench-only, to tell the library's speed from the formula's layout."""
    from motiondiff.geometry.kinematics import forward_kinematics
    from motiondiff.geometry.rotations import quat_to_matrix

    shaped, joints = body.shaped(betas), body.rest_joints(betas)
    offsets = joints - np.where(body.parents[:, None] >= 0, joints[np.maximum(body.parents, 0)], 0.0)
    local = np.repeat(offsets[None], len(rotations), axis=0)
    local[:, 0] = joints[0] + trans
    positions, world = forward_kinematics(rotations, local, body.parents)
    world_m = quat_to_matrix(world)
    feature = (quat_to_matrix(rotations[:, 1:]) - np.eye(3)).reshape(len(rotations), -1)
    posed = shaped + (feature @ body.posedirs.reshape(VERTICES * 3, -1).T).reshape(len(rotations), VERTICES, 3)
    shift = positions - np.einsum("njab,jb->nja", world_m, joints)
    blend = body.weights @ np.concatenate([world_m.reshape(len(rotations), JOINTS, 9), shift], axis=-1)
    return (blend[..., :9].reshape(len(rotations), VERTICES, 3, 3) @ posed[..., None])[..., 0] + blend[..., 9:]


def smplx_args(body: SmplBody, poses: np.ndarray, betas: np.ndarray, dtype: torch.dtype) -> dict:
    def t(a):
        return torch.as_tensor(np.ascontiguousarray(a), dtype=dtype)

    frames = len(poses)
    return {"betas": t(np.repeat(betas[None], frames, 0)), "pose": t(poses.reshape(frames, -1)),
            "v_template": t(body.v_template), "shapedirs": t(body.shapedirs),
            "posedirs": t(body.posedirs.reshape(VERTICES * 3, -1).T), "J_regressor": t(body.J_regressor),
            "parents": torch.as_tensor(body.parents), "lbs_weights": t(body.weights)}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--frames", type=int, default=64, help="poses skinned in one call (render=mesh's chunk)")
    args = parser.parse_args(argv)
    rng = np.random.default_rng(1)
    body = random_body()
    poses = rng.normal(scale=0.5, size=(args.frames, JOINTS, 3))
    trans, betas = rng.normal(size=(args.frames, 3)), rng.normal(size=SHAPES)
    rotations = rotvec_to_quat(poses)

    def ours():
        return body.vertices(rotations, trans, betas)

    def theirs(dtype):
        kw = smplx_args(body, poses, betas, dtype)
        shift = torch.as_tensor(trans, dtype=dtype)[:, None]

        def run():
            with torch.no_grad():
                verts, joints = lbs(**kw)
            return verts + shift, joints + shift

        return run

    v_ours = ours()
    result = {"frames": args.frames, "vertices": VERTICES, "joints": JOINTS}
    for name, dtype in (("float32", torch.float32), ("float64", torch.float64)):
        v_theirs, j_theirs = theirs(dtype)()
        result[f"smplx_{name}"] = {
            "vertices_max_abs_difference_m": max_abs(v_ours, v_theirs),
            "speed": speed(ours, theirs(dtype), repeats=5),
        }
    result["project_formula_as_one_matmul"] = {
        "vertices_max_abs_difference_m": max_abs(v_ours, matmul_skinning(body, rotations, trans, betas)),
        "speed_vs_smplx_float32": speed(lambda: matmul_skinning(body, rotations, trans, betas), theirs(torch.float32),
                                        repeats=5),
    }  # fmt: skip
    joints_ours = body.J_regressor @ body.shaped(betas)  # rest joints: the same regression on both sides
    kw = smplx_args(body, poses, betas, torch.float64)
    result["rest_joints_max_abs_difference_m"] = max_abs(
        joints_ours,
        (kw["J_regressor"] @ (kw["v_template"] + torch.einsum("l,mkl->mk", kw["betas"][0], kw["shapedirs"]))),
    )
    result["size"] = {"smplx": install_cost("smplx"), "smplx_import_s": import_seconds("smplx")}
    write("smpl_skinning", result)
    print(result)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
