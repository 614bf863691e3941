"""render=body: videos of the mannequin (`geometry.mannequin`), a low-poly body made in code from the motion's own
skeleton, so a body shows without the licence-restricted SMPL model and on any skeleton (SMPL-22, KIT-21, a BVH rig).

The mannequin is sized on the motion's own bone lengths (`fit_rest_offsets`) and posed from its joints directly (no
IK). This module gives only its mesh: `export.outputs` draws it as it draws the SMPL body, with `mesh_render`'s
camera, ground, trail, titles and video writers.
"""

from __future__ import annotations

import numpy as np

from motiondiff.geometry.inverse_kinematics import fit_rest_offsets
from motiondiff.geometry.mannequin import build_mannequin
from motiondiff.geometry.skeleton import Skeleton


class MannequinBody:
    """What `smpl_mesh.render_body` gives for render=body: the videos show the mannequin (no model file to load)."""

    def __repr__(self) -> str:
        return "MannequinBody()"


MANNEQUIN = MannequinBody()


def mannequin_mesh(joints: np.ndarray, skeleton: Skeleton) -> tuple[np.ndarray, np.ndarray]:
    """(vertices (N, V, 3), faces (F, 3)) of the mannequin posed by joints (N, J, 3) of `skeleton`."""
    joints = np.asarray(joints, dtype=np.float64)
    mannequin = build_mannequin(skeleton, fit_rest_offsets(joints, skeleton))
    return mannequin.at(joints), mannequin.faces
