"""SMPL body meshes of a motion, for the CLIs' render=mesh videos: the motion's joints (SMPL-22 or SMPL-24) become
SMPL pose parameters by the same IK as export=smpl (`smpl_parameters`), which pose the user's SMPL body model by
linear blend skinning (`SmplBody.vertices`) at the mean shape (zero betas).

The model is licence-restricted and never shipped: the user points to it with smpl_model=. SMPL+H and SMPL-X model
files (52 or 55 joints) work too: their first 22 joints are SMPL's body, and their other joints (hands, face) stay
at rest, as SMPL's two hand joints do for a SMPL-22 motion. The pelvis is placed on the motion's root, whatever the
model's own rest pelvis, so the body walks where the stick figure does.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from motiondiff.data.formats.smpl_params import BODY_JOINTS, SmplBody, SmplParamsError, load_smpl_body
from motiondiff.export.body_render import MANNEQUIN, MannequinBody
from motiondiff.export.smpl_export import SMPL_NEUTRAL_PELVIS, check_smpl_skeleton, smpl_parameters
from motiondiff.geometry.rotations import rotvec_to_quat
from motiondiff.geometry.skeleton import SMPL22, SMPL24, Skeleton
from motiondiff.runtime.errors import UsageError

RENDERS = ("stick", "mesh", "body")
GET_MODEL = ("the SMPL body model is licence-restricted and not shipped: register at smpl.is.tue.mpg.de, download "
             "the model (or SMPL-X/SMPL+H), save it as a .npz of plain arrays and pass smpl_model=<path to the "
             "model .npz>")  # fmt: skip
CHUNK = 64  # frames posed at once: bounds the skinning's memory (about 1.5 MB per frame for SMPL)


def render_body(render: str | None, smpl_model: str | Path | None) -> SmplBody | MannequinBody | None:
    """The body the videos show for ``render=`` (stick: None; body: the mannequin, `body_render.MANNEQUIN`; mesh: the
    SMPL model at ``smpl_model=``, loaded and checked for a mesh); one UsageError naming the fix for an unknown value,
    a missing or unusable model file."""
    choice = "stick" if render is None else str(render).strip().lower()
    if choice not in RENDERS:
        raise UsageError(f"unknown render={render!r}: choose stick (stick-figure videos), body (a mannequin, no model "
                         "file) or mesh (an SMPL body mesh; needs smpl_model=)")  # fmt: skip
    if choice in ("stick", "body"):
        if smpl_model is not None:
            raise UsageError(f"smpl_model={smpl_model} is the body of render=mesh videos: add render=mesh, or drop "
                             f"smpl_model= for {'stick figures' if choice == 'stick' else 'the mannequin'}")  # fmt: skip
        return MANNEQUIN if choice == "body" else None
    if smpl_model is None or not str(smpl_model).strip():
        raise UsageError(f"render=mesh draws an SMPL body: {GET_MODEL}")
    try:
        body = load_smpl_body(smpl_model)
    except SmplParamsError as err:
        raise UsageError(str(err)) from None
    source = f"smpl_model={smpl_model}"
    if body.weights is None or body.faces is None:
        raise UsageError(f"{source}: has no skinning weights or faces (weights, f), which a mesh needs; give the full "
                         "model file")  # fmt: skip
    faces = np.asarray(body.faces)
    if faces.ndim != 2 or faces.shape[1] != 3 or faces.dtype.kind not in "iu" or not len(faces):
        raise UsageError(f"{source}: its faces f must be vertex indices of shape (F, 3), got {faces.shape}")
    if faces.min() < 0 or faces.max() >= len(body.v_template):
        raise UsageError(f"{source}: its faces index vertices up to {faces.max()}, but it has {len(body.v_template)}")
    if tuple(body.parents[:BODY_JOINTS]) != tuple(SMPL22.parents):
        raise UsageError(f"{source}: its first {BODY_JOINTS} joints are not SMPL's body joints; give an SMPL, SMPL+H "
                         "or SMPL-X model file")  # fmt: skip
    return body


def check_mesh_skeleton(skeleton: Skeleton) -> int:
    """22 or 24 (the SMPL joints of the motion); UsageError for any other skeleton, before anything is generated."""
    return check_smpl_skeleton(skeleton, "render=mesh", "use render=stick (stick figures) or render=body (a "
                               "mannequin, any skeleton) for it")  # fmt: skip


def smpl_vertices(joints: np.ndarray, skeleton: Skeleton, fps: float, body: SmplBody) -> np.ndarray:
    """The body's meshes (N, V, 3) (metres, y up) posed by joints (N, 22 or 24, 3) of `skeleton` (module doc)."""
    check_mesh_skeleton(skeleton)
    data, _, _ = smpl_parameters(joints, skeleton, fps)
    frames = len(data["poses"])
    solved = rotvec_to_quat(data["poses"].reshape(frames, -1, 3))  # (N, 24, 4): SMPL's joints, hands at rest
    rotations = np.zeros((frames, len(body.parents), 4))
    rotations[..., 0] = 1.0
    same = len(body.parents) == SMPL24.num_joints  # SMPL's joints 22, 23 are its hands; SMPL+H/X use them otherwise
    kept = SMPL24.num_joints if same else BODY_JOINTS
    rotations[:, :kept] = solved[:, :kept]  # a SMPL-24 motion's hand turns have no joint in SMPL+H/X: left at rest
    trans = data["trans"] + SMPL_NEUTRAL_PELVIS - body.rest_joints()[0]  # the model's pelvis on the motion's root
    return np.concatenate([body.vertices(rotations[s : s + CHUNK], trans[s : s + CHUNK])
                           for s in range(0, frames, CHUNK)])  # fmt: skip
