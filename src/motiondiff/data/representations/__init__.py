"""Motion representations: HumanML3D features (hml263 / kit251) and the six vvMDM layouts (jp, rp6jr, rpqjr,
rpajr, rpejr, rpmjr). `get_representation` builds one from its name and the dataset's skeletons."""

from __future__ import annotations

from motiondiff.data.representations.base import Representation
from motiondiff.data.representations.hml import HMLRepresentation
from motiondiff.data.representations.rig import EULER_ORDER, JointPositions, RotationRepresentation
from motiondiff.geometry.skeleton import Skeleton
from motiondiff.runtime.errors import RepresentationError

REPRESENTATIONS = ("hml263", "kit251", "jp", "rp6jr", "rpqjr", "rpajr", "rpejr", "rpmjr")
ROTATION_REPRESENTATIONS = ("rp6jr", "rpqjr", "rpajr", "rpejr", "rpmjr")
_HML = {"hml263": 22, "kit251": 21}  # joints of the feature skeleton each HumanML3D layout is defined for

__all__ = [
    "EULER_ORDER",
    "REPRESENTATIONS",
    "ROTATION_REPRESENTATIONS",
    "HMLRepresentation",
    "JointPositions",
    "Representation",
    "RotationRepresentation",
    "get_representation",
]


def _hml_name(skeleton: Skeleton) -> str | None:
    return next((n for n, j in _HML.items() if j == skeleton.num_joints), None)


def get_representation(name: str, feature_skeleton: Skeleton, rig: Skeleton | None = None) -> Representation:
    """The representation `name` for a dataset whose clips have `feature_skeleton` joints (SMPL-22 / KIT-21) and,
    when the source has rotations, a rotation `rig`."""
    if name not in REPRESENTATIONS:
        raise RepresentationError(f"unknown representation {name!r}; choose from {', '.join(REPRESENTATIONS)}")
    if name in _HML:
        if feature_skeleton.num_joints != _HML[name]:
            right = _hml_name(feature_skeleton)
            hint = f"use {right!r}" if right else "hml263 needs SMPL-22 joints, kit251 KIT-21 joints"
            raise RepresentationError(
                f"{name} is defined for a {_HML[name]}-joint feature skeleton, but this dataset's is "
                f"{feature_skeleton.name!r} ({feature_skeleton.num_joints} joints): {hint}"
            )
        return HMLRepresentation(name, feature_skeleton)
    if name == "jp":
        return JointPositions(rig if rig is not None else feature_skeleton, uses_rig=rig is not None)
    if rig is None:
        hml = _hml_name(feature_skeleton) or "hml263/kit251"
        raise RepresentationError(
            f"{name} needs joint rotations, but this dataset stores joint positions only (no rotation rig); "
            f"representations that work on it: {hml}, jp"
        )
    return RotationRepresentation(name, rig)
