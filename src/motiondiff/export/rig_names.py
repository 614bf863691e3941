"""Bone names of common rigs (SMPL, Mixamo) for exported motion files, so a BVH/FBX/GLB retargets onto those rigs
by name. The names are data (motiondiff/assets/rig_names.json); only the joint names change, never the motion."""

from __future__ import annotations

import dataclasses
import json
from functools import cache
from importlib import resources

from motiondiff.geometry.skeleton import Skeleton
from motiondiff.runtime.errors import UsageError


@cache
def _table() -> dict:
    return json.loads((resources.files("motiondiff") / "assets" / "rig_names.json").read_text(encoding="utf-8"))


def rig_presets() -> list[str]:
    return sorted(_table()["presets"])


def with_rig_names(skeleton: Skeleton, preset: str | None) -> Skeleton:
    """``skeleton`` with its joints named as the rig ``preset`` names them (None: unchanged)."""
    if preset is None:
        return skeleton
    table = _table()
    if preset not in table["presets"]:
        raise UsageError(f"unknown joint-name preset {preset!r}; choose from {', '.join(rig_presets())} (or null)")
    names = table["presets"][preset]
    if skeleton.name != table["skeleton"] or set(skeleton.joint_names) != set(names):
        raise UsageError(f"joint-name presets name the {table['skeleton']} skeleton's joints; this motion is on "
                         f"{skeleton.name!r}: export it without bvh_names")  # fmt: skip
    return dataclasses.replace(skeleton, joint_names=tuple(names[n] for n in skeleton.joint_names))
