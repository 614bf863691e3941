"""Joint mappings between skeletons, kept as data (JSON files in motiondiff/assets/).

A map says, for every joint of the target skeleton, which source joints it is the mean of (usually one; e.g. SMPL's
spine2 is the midpoint of Bandai's Spine and Chest), plus the factor that converts the source units to metres.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

from motiondiff.data.formats.joint_infer import guess_units, infer_smpl22
from motiondiff.geometry.skeleton import get_skeleton


@dataclass(frozen=True)
class JointMap:
    source: str
    target: str
    units_to_metres: float
    joints: dict[str, list[str]]  # target joint name -> source joint names (averaged)

    @classmethod
    def load(cls, name_or_path: str | Path) -> JointMap:
        """A shipped map by name (e.g. 'bandai_to_smpl22') or a JSON file of the same format."""
        path = Path(name_or_path)
        if path.suffix != ".json":
            path = resources.files("motiondiff") / "assets" / f"{name_or_path}.json"
        try:
            spec = json.loads(Path(str(path)).read_text())
        except FileNotFoundError:
            shipped = sorted(p.name[:-5] for p in (resources.files("motiondiff") / "assets").iterdir())
            raise FileNotFoundError(f"joint map {name_or_path!r} not found; shipped maps: {shipped}") from None
        keys = ("source", "target", "units_to_metres", "joints")
        if not isinstance(spec, dict) or any(k not in spec for k in keys) or not isinstance(spec["joints"], dict):
            raise ValueError(f"joint map {path} must be a JSON object with {', '.join(keys)} (joints: target joint -> "
                             "source joint); see the shipped maps in motiondiff/assets")  # fmt: skip
        target = get_skeleton(spec["target"])
        missing = [j for j in target.joint_names if j not in spec["joints"]]
        if missing:
            raise ValueError(f"joint map {path} does not define target joints {missing}")
        return cls(spec["source"], spec["target"], float(spec["units_to_metres"]), spec["joints"])

    @classmethod
    def infer(
        cls,
        source_names,
        parents,
        units_to_metres: float | None = None,
        *,
        offsets: np.ndarray | None = None,
        source: str = "bvh",
    ) -> JointMap:
        """Guess the SMPL-22 map of a skeleton from its joint names (see motiondiff.data.formats.joint_infer for the
        conventions read and the unit guess). `offsets` (J, 3) rest offsets are needed to guess the units when
        `units_to_metres` is not given; they also let joints that sit on their parent (zero offset, as CMU's
        LowerBack or Neck) be skipped. Raises one ValueError naming every SMPL joint that cannot be matched."""

        joints = infer_smpl22(list(source_names), [int(p) for p in parents], offsets)
        if units_to_metres is None:
            if offsets is None:
                raise ValueError("JointMap.infer: pass units_to_metres, or offsets to guess the units from")
            units_to_metres = guess_units(list(source_names), [int(p) for p in parents], offsets, joints)
        return cls(source, "smpl22", float(units_to_metres), joints)

    def source_joints(self) -> set[str]:
        """Every source joint the map reads (a skeleton lacking one cannot be mapped)."""
        return {s for names in self.joints.values() for s in names}

    def to_json(self) -> dict:
        """The map in the format of the shipped JSON files (what --joint-map path.json reads)."""
        return {"source": self.source, "target": self.target, "units_to_metres": self.units_to_metres,
                "joints": self.joints}  # fmt: skip

    def weights(self, source_names: list[str]) -> np.ndarray:
        """(J_target, J_source) averaging matrix for a source skeleton with these joint names."""
        target = get_skeleton(self.target)
        w = np.zeros((target.num_joints, len(source_names)))
        for t, name in enumerate(target.joint_names):
            for src in self.joints[name]:
                if src not in source_names:
                    raise ValueError(
                        f"joint map {self.source}->{self.target} needs source joint {src!r}, which this skeleton "
                        f"lacks (joints: {', '.join(source_names)})"
                    )
                w[t, source_names.index(src)] = 1.0 / len(self.joints[name])
        return w

    def apply(self, positions: np.ndarray, source_names: list[str], to_metres: bool = True) -> np.ndarray:
        """Source positions (..., J_source, 3) -> target positions (..., J_target, 3), in metres by default."""
        out = np.einsum("ts,...sc->...tc", self.weights(source_names), positions)
        return out * self.units_to_metres if to_metres else out
