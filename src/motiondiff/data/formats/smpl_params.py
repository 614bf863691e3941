"""SMPL pose parameters as motion input (AMASS `.npz`, the SMPL/SMPL-X add-ons' files, this project's export=smpl):
read as a BVH-like motion of SMPL's 22 body joints, so they go through the same preparation as a BVH file.

A parameter file holds local axis-angle rotations (`poses`, or `global_orient` + `body_pose`, or AMASS SMPL-X's
`root_orient` + `pose_body`), a root translation `trans` and body shape `betas`; it does not hold the skeleton. The
rest joints come from:
- the file itself when it records them (`rest_offsets`, written by this project's export=smpl), or
- an SMPL body model the user has (`SmplBody`, a `.npz` with `v_template`, `shapedirs`, `J_regressor`,
  `kintree_table`, and for meshes `weights`, `f`, `posedirs`): the rest joints are J_regressor (v_template +
  shapedirs betas), and the pelvis is at J_0 + trans, as the SMPL model places it.
The body models are licence-restricted and never shipped; a file that needs one gets a message naming it. The first
22 joints are the body in SMPL, SMPL+H and SMPL-X alike, so any of their parameter files reads.

Written here rather than taken from the `smplx` package: that package carries the model files' non-commercial
licence and needs torch for what is a few lines of numpy (rest joints, and linear blend skinning for meshes).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from motiondiff.data.formats.array_bounds import check_array_file
from motiondiff.data.formats.bvh import BVHMotion, motion_from_arrays
from motiondiff.geometry.kinematics import forward_kinematics
from motiondiff.geometry.rotations import quat_to_matrix, rotvec_to_quat
from motiondiff.geometry.skeleton import SMPL22

BODY_JOINTS = 22
POSE_KEYS = (("poses",), ("global_orient", "body_pose"), ("root_orient", "pose_body"))
FPS_KEYS = ("mocap_framerate", "mocap_frame_rate", "fps")
MODEL_KEYS = ("v_template", "shapedirs", "J_regressor", "kintree_table")
NEEDS_MODEL = ("computing its joints needs the SMPL body model, which is licence-restricted and not shipped: get it "
               "from smpl.is.tue.mpg.de (or SMPL-X/SMPL+H for those files) and pass smpl_model=<the model .npz>")  # fmt: skip


class SmplParamsError(ValueError):
    """A parameter or body-model file that cannot be read as one; the message names the file and the fix."""


def is_smpl_params(names) -> bool:
    """Whether an `.npz` with these array names holds SMPL parameters (rather than joint positions)."""
    names = set(names)
    return "trans" in names and any(set(keys) <= names for keys in POSE_KEYS)


@dataclass(frozen=True)
class SmplBody:
    """An SMPL-family body model: template mesh (V, 3), shape directions (V, 3, B), joint regressor (J, V), parents
    (J,); for meshes also skinning weights (V, J), faces (F, 3) and pose correctives (V, 3, 9 (J - 1)) if present."""

    v_template: np.ndarray
    shapedirs: np.ndarray
    J_regressor: np.ndarray  # noqa: N815 (the models' own name)
    parents: np.ndarray
    weights: np.ndarray | None = None
    faces: np.ndarray | None = None
    posedirs: np.ndarray | None = None
    source: str = "<memory>"

    def shaped(self, betas=None) -> np.ndarray:
        """The rest mesh (V, 3) for shape `betas` (missing ones zero, extra ones ignored)."""
        betas = np.zeros(0) if betas is None else np.asarray(betas, dtype=np.float64).ravel()
        count = min(len(betas), self.shapedirs.shape[-1])
        return self.v_template + self.shapedirs[..., :count] @ betas[:count]

    def rest_joints(self, betas=None) -> np.ndarray:
        """Rest joint positions (J, 3) for shape `betas`."""
        return self.J_regressor @ self.shaped(betas)

    def vertices(self, rotations: np.ndarray, trans: np.ndarray, betas=None) -> np.ndarray:
        """Posed meshes (N, V, 3) by linear blend skinning: local rotations (N, J, 4) (w, x, y, z; the root's
        global), root translations (N, 3) (the pelvis at J_0 + trans)."""
        if self.weights is None or self.faces is None:
            raise SmplParamsError(f"{self.source}: the body model has no skinning weights or faces (`weights`, `f`); "
                                  "a mesh needs the full model file")  # fmt: skip
        shaped, joints = self.shaped(betas), self.rest_joints(betas)
        offsets = joints - np.where(self.parents[:, None] >= 0, joints[np.maximum(self.parents, 0)], 0.0)
        local = np.repeat(offsets[None], len(rotations), axis=0)
        local[:, 0] = joints[0] + trans
        positions, world = forward_kinematics(rotations, local, self.parents)
        world_m = quat_to_matrix(world)  # (N, J, 3, 3)
        posed = np.broadcast_to(shaped, (len(rotations),) + shaped.shape).copy()
        if self.posedirs is not None:  # pose correctives: (R_j - I) of every non-root joint, SMPL's pose feature
            feature = (quat_to_matrix(rotations[:, 1:]) - np.eye(3)).reshape(len(rotations), -1)
            posed += np.einsum("vcp,np->nvc", self.posedirs[..., : feature.shape[1]], feature)
        shift = positions - np.einsum("njab,jb->nja", world_m, joints)  # each joint's transform: R_j x + shift_j
        blend_r = np.einsum("vj,njab->nvab", self.weights, world_m)
        blend_t = np.einsum("vj,nja->nva", self.weights, shift)
        return np.einsum("nvab,nvb->nva", blend_r, posed) + blend_t


def load_smpl_body(path) -> SmplBody:
    """An SMPL-family model from a `.npz` of plain arrays (module doc), checked for shapes."""
    path = Path(path)
    if path.suffix.lower() != ".npz":
        raise SmplParamsError(f"smpl_model={path}: give the model as a .npz of plain arrays ({', '.join(MODEL_KEYS)}, "
                              "weights, f, posedirs); a .pkl holds chumpy objects: convert it with smplx's "
                              "tools/clean_ch.py and numpy.savez")  # fmt: skip
    if not path.is_file():
        raise SmplParamsError(f"smpl_model={path} not found (relative to {Path.cwd()}); check the path")
    try:
        check_array_file(path)  # from the headers: a few MB of .npz may inflate to GBs
        with np.load(path, allow_pickle=False) as data:
            arrays = {k: np.asarray(data[k]) for k in data.files if k in (*MODEL_KEYS, "weights", "f", "posedirs")}
    except (ValueError, OSError, EOFError) as err:
        raise SmplParamsError(f"smpl_model={path}: not a readable .npz of plain arrays ({err})") from None
    missing = [k for k in MODEL_KEYS if k not in arrays]
    if missing:
        raise SmplParamsError(f"smpl_model={path}: lacks {', '.join(missing)}; an SMPL model .npz holds "
                              f"{', '.join(MODEL_KEYS)} (and weights, f, posedirs for meshes)")  # fmt: skip
    v = arrays["v_template"].astype(np.float64)
    shapedirs = arrays["shapedirs"].astype(np.float64)
    regressor = arrays["J_regressor"].astype(np.float64)
    parents = arrays["kintree_table"][0].astype(np.int64)
    parents[0] = -1
    joints = len(regressor)
    problems = [
        v.ndim != 2 or v.shape[1] != 3,
        shapedirs.shape[:2] != v.shape,
        regressor.ndim != 2 or regressor.shape[1] != len(v) or joints < BODY_JOINTS,
        len(parents) != joints or any(not 0 <= p < j for j, p in enumerate(parents[1:], 1)),
        "weights" in arrays and arrays["weights"].shape != (len(v), joints),
    ]
    if any(problems) or not all(np.isfinite(a).all() for a in (v, shapedirs, regressor)):
        raise SmplParamsError(f"smpl_model={path}: its arrays do not fit together as an SMPL model (v_template "
                              f"{v.shape}, shapedirs {shapedirs.shape}, J_regressor {regressor.shape}, kintree_table "
                              f"{arrays['kintree_table'].shape}); give the model file itself")  # fmt: skip
    posedirs = arrays.get("posedirs")
    if posedirs is not None:
        posedirs = posedirs.astype(np.float64).reshape(len(v), 3, -1)
    return SmplBody(v, shapedirs, regressor, parents, arrays.get("weights"), arrays.get("f"), posedirs, str(path))


def read_smpl_params(path, body: SmplBody | None = None) -> BVHMotion:
    """The 22 body joints of an SMPL parameter `.npz` as a motion (metres, the file's own up axis and frame rate)."""
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {k: np.asarray(data[k]) for k in data.files if data[k].dtype.kind in "fiu"}
    except (ValueError, OSError, EOFError) as err:
        raise SmplParamsError(f"{path}: not a readable .npz of plain arrays ({err})") from None
    poses = _body_poses(arrays, path)
    trans = arrays["trans"].astype(np.float64)
    if trans.shape != (len(poses), 3):
        raise SmplParamsError(f"{path}: trans must be ({len(poses)}, 3) for its {len(poses)} poses, got {trans.shape}")
    fps = next((float(arrays[k]) for k in FPS_KEYS if k in arrays and arrays[k].size == 1), None)
    if fps is None or not np.isfinite(fps) or fps <= 0:
        raise SmplParamsError(f"{path}: holds no positive frame rate ({' or '.join(FPS_KEYS)}); add one")
    if "rest_offsets" in arrays and arrays["rest_offsets"].shape[0] >= BODY_JOINTS:  # this project's export=smpl
        offsets = arrays["rest_offsets"][:BODY_JOINTS].astype(np.float64)
        root = trans + offsets[0]
    elif body is not None:
        joints = body.rest_joints(arrays.get("betas"))[:BODY_JOINTS]
        parents = np.asarray(SMPL22.parents)
        if tuple(body.parents[:BODY_JOINTS]) != tuple(parents):
            raise SmplParamsError(f"{body.source}: its first {BODY_JOINTS} joints are not SMPL's body joints")
        offsets = joints - np.where(parents[:, None] >= 0, joints[np.maximum(parents, 0)], 0.0)
        root = trans + joints[0]
    else:
        raise SmplParamsError(f"{path} holds SMPL parameters (poses, trans, betas) but not the skeleton; {NEEDS_MODEL}")
    if not (np.isfinite(poses).all() and np.isfinite(root).all() and np.isfinite(offsets).all()):
        raise SmplParamsError(f"{path}: its poses or translations contain NaN or Inf")
    rotations = rotvec_to_quat(poses.reshape(len(poses), BODY_JOINTS, 3))
    offsets[0] = 0.0
    return motion_from_arrays(SMPL22.joint_names, SMPL22.parents, offsets, rotations, root, fps, source=str(path))


def _body_poses(arrays: dict, path: Path) -> np.ndarray:
    """(N, 66): the axis-angle rotations of the 22 body joints (root first)."""
    for keys in POSE_KEYS:
        if set(keys) <= set(arrays):
            parts = [arrays[k].astype(np.float64) for k in keys]
            parts = [p.reshape(len(p), -1) if p.ndim >= 2 else p for p in parts]
            if any(p.ndim != 2 or len(p) != len(parts[0]) for p in parts):
                break
            poses = np.concatenate(parts, axis=1)
            if poses.shape[1] >= 3 * BODY_JOINTS and poses.shape[1] % 3 == 0 and len(poses) > 0:
                return poses[:, : 3 * BODY_JOINTS]
            break
    raise SmplParamsError(f"{path}: SMPL poses must be (frames, 3 x joints) axis-angles with at least the "
                          f"{BODY_JOINTS} body joints (poses, or global_orient + body_pose); got "
                          f"{ {k: arrays[k].shape for k in arrays} }")  # fmt: skip
