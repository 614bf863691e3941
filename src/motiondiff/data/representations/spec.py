"""A representation as plain data (what a checkpoint stores) and the bridge from it to the evaluators' features.

A trained model must decode its samples without the dataset, so the checkpoint keeps the representation's name, the
feature skeleton's name and, for rig representations, the rig (names, parents, mean offsets) plus the joint map that
puts rig joints onto the feature skeleton. The evaluators read HumanML3D features; `HMLBridge` turns any
representation's de-normalised features into them the way the dataset made its own: decode to joints, map to SMPL-22
(or KIT-21), canonicalise, compute the features.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from motiondiff.data.formats.joint_map import JointMap
from motiondiff.data.representations import Representation, get_representation
from motiondiff.data.representations.hml_features import canonicalize_joints, features_from_canonical, skeleton_for_dim
from motiondiff.geometry.skeleton import SKELETONS, Skeleton, get_skeleton


def representation_spec(rep: Representation, feature_skeleton: Skeleton, joint_map: JointMap | None = None) -> dict:
    """Plain data (JSON-able) that `representation_from_spec` and `bridge_from_spec` rebuild from."""
    spec: dict = {"name": rep.name, "feature_skeleton": feature_skeleton.name, "rig": None, "joint_map": None}
    if joint_map is not None:
        spec["joint_map"] = dataclasses.asdict(joint_map)
    if rep.skeleton is not feature_skeleton and rep.skeleton.name != feature_skeleton.name:
        s = rep.skeleton
        spec["rig"] = {
            "name": s.name,
            "joint_names": list(s.joint_names),
            "parents": list(s.parents),
            "offsets": np.asarray(s.offsets, dtype=np.float64).tolist(),
            "fps": s.fps,
        }
    return spec


def rig_from_spec(rig: dict) -> Skeleton:
    offsets = np.asarray(rig["offsets"], dtype=np.float64)
    if rig["name"] in SKELETONS:  # a defined skeleton (e.g. SMPL-24) keeps its own parts; only the bones differ
        return SKELETONS[rig["name"]].with_offsets(offsets)
    return Skeleton.infer(rig["name"], rig["joint_names"], rig["parents"], offsets, fps=rig.get("fps"))


def representation_from_spec(spec: dict | None, feature_dim: int | None = None) -> Representation:
    """Rebuild the representation of a checkpoint; old checkpoints (no spec) used HumanML3D features."""
    if spec is None:
        skel = skeleton_for_dim(int(feature_dim))
        return get_representation("hml263" if skel.num_joints == 22 else "kit251", skel)
    feature_skeleton = get_skeleton(spec["feature_skeleton"])
    rig = rig_from_spec(spec["rig"]) if spec.get("rig") else None
    return get_representation(spec["name"], feature_skeleton, rig)


def bridge_from_spec(spec: dict | None, feature_dim: int | None = None) -> HMLBridge:
    rep = representation_from_spec(spec, feature_dim)
    if spec is None:
        return HMLBridge(rep, rep.skeleton)
    joint_map = JointMap(**spec["joint_map"]) if spec.get("joint_map") else None
    return HMLBridge(rep, get_skeleton(spec["feature_skeleton"]), joint_map)


class HMLBridge:
    """De-normalised features of `rep` -> HumanML3D features of the feature skeleton (identity for hml263/kit251).

    Rig joints reach the feature skeleton through `joint_map`, or by taking the first joints when the rig starts
    with the feature skeleton's joints (SMPL-24 -> SMPL-22)."""

    def __init__(self, rep: Representation, feature_skeleton: Skeleton, joint_map: JointMap | None = None):
        self.rep, self.feature_skeleton = rep, feature_skeleton
        self.identity = rep.name in ("hml263", "kit251")
        self.weights = None
        if not self.identity and rep.skeleton.name != feature_skeleton.name:
            if joint_map is not None:
                self.weights = joint_map.weights(list(rep.skeleton.joint_names))
            elif rep.skeleton.joint_names[: feature_skeleton.num_joints] != feature_skeleton.joint_names:
                raise ValueError(
                    f"no joint map from {rep.skeleton.name!r} to {feature_skeleton.name!r}: evaluation needs one "
                    "(a prepared dataset stores it in meta.json)"
                )

    def joints(self, features: np.ndarray) -> np.ndarray:
        """(N, D) de-normalised features -> (N, Jf, 3) joints of the feature skeleton (not canonicalised)."""
        pos = self.rep.decode_numpy(features)
        if self.weights is not None:
            return np.einsum("ts,nsc->ntc", self.weights, pos)
        return pos[:, : self.feature_skeleton.num_joints]

    def __call__(self, features: np.ndarray) -> np.ndarray:
        if self.identity:
            return features
        joints = canonicalize_joints(self.joints(features), self.feature_skeleton)
        return features_from_canonical(joints, self.feature_skeleton).astype(np.float32)
