"""Guess how a mocap skeleton maps onto SMPL-22 from its joint names and hierarchy (`JointMap.infer`).

Names are read after dropping a rig namespace ("mixamorig:", "Bip01 ") and the side ("Left", "L_", "_L", or a
glued "l" as in ASF's "lfemur"); what is left is matched against the aliases below, in order of preference:

    convention        hip          knee          ankle       foot         collar         shoulder   elbow        wrist
    Bandai            UpperLeg_L   LowerLeg_L    Foot_L      Toes_L       Shoulder_L     UpperArm_L LowerArm_L   Hand_L
    CMU / Mixamo      LeftUpLeg    LeftLeg       LeftFoot    LeftToeBase  LeftShoulder   LeftArm    LeftForeArm  LeftHand
    100STYLE (Xsens)  LeftHip      LeftKnee      LeftAnkle   LeftToe      LeftCollar     LeftShoulder LeftElbow  LeftWrist
    SMPL              L_Hip        L_Knee        L_Ankle     L_Foot       L_Collar       L_Shoulder L_Elbow      L_Wrist

"Shoulder" is the clavicle where no Collar/Clavicle joint exists (CMU, Mixamo) and the upper arm otherwise
(100STYLE). The torso is read from the hierarchy: pelvis = the joint where the two legs meet; head = the joint
named Head; neck = the first Neck-named joint on the way to the head; the spine joints between pelvis and neck,
up to the joint the arms hang from, give spine1 (first), spine3 (last) and spine2 (middle; the mean of the two
middle ones for an even count, the mean of spine1 and spine3 for two joints, as the Bandai map does). SMPL
joints without a counterpart are the mean of their neighbours: a missing collar is mean(spine3, shoulder),
a missing neck mean(spine3, head). Joints with a zero offset sit on their parent and duplicate its position, so
with `offsets` they are skipped in the spine and neck, and a zero-offset collar becomes mean(collar, shoulder).
"""

from __future__ import annotations

import re

import numpy as np

from motiondiff.geometry.skeleton import SMPL22_NAMES, _tokens

LIMB_ALIASES = {
    "hip": ("upleg", "upperleg", "thigh", "femur", "hip"),
    "knee": ("lowerleg", "lowleg", "knee", "shin", "calf", "tibia", "leg"),
    "ankle": ("ankle", "foot"),
    "foot": ("toebase", "toe", "toes", "ball", "foot"),
    "collar": ("collar", "clavicle", "shoulder"),
    "shoulder": ("upperarm", "uparm", "arm", "humerus", "shoulder"),
    "elbow": ("forearm", "lowerarm", "lowarm", "elbow", "radius"),
    "wrist": ("wrist", "hand"),
}
LEG, ARM = ("hip", "knee", "ankle", "foot"), ("collar", "shoulder", "elbow", "wrist")
_KNOWN = {a for aliases in LIMB_ALIASES.values() for a in aliases} | {"hipjoint"}
_PREFIX = re.compile(r"^(.*:|bip0*1[ _]|mixamorig\d*_)", re.I)

# Leg length (hip to ankle) of an adult, and the unit conventions it tells apart (factor to metres).
LEG_METRES = 0.8
UNITS = {"metres": 1.0, "centimetres": 0.01, "millimetres": 0.001, "inches": 0.0254,
         "CMU ASF units (1/0.45 inch)": 0.0254 / 0.45}  # fmt: skip
PLAUSIBLE_LEG = (0.4, 2.0)

HOW_TO_MAP = (
    "pass --joint-map path.json (or JointMap.load(path)) with a map in the format of "
    'motiondiff/assets/bandai_to_smpl22.json: {"source": ..., "target": "smpl22", "units_to_metres": ..., '
    '"joints": {"pelvis": ["Hips"], "spine2": ["Spine", "Chest"], ...}}, each SMPL joint the mean of '
    "the listed source joints"
)


def side_and_part(name: str) -> tuple[str | None, str]:
    """('left' | 'right' | None, name without rig prefix and side, lower case): 'mixamorig:LeftUpLeg' -> upleg."""
    tokens = _tokens(_PREFIX.sub("", name))
    side, rest = None, []
    for t in tokens:
        if side is None and t in ("left", "l", "right", "r"):
            side = "left" if t[0] == "l" else "right"
        else:
            rest.append(t)
    part = "".join(rest)
    if side is None:
        for glued in ("left", "right", "l", "r"):  # 'lfemur', 'LHipJoint', 'leftfoot'
            if part.startswith(glued) and part[len(glued) :] in _KNOWN:
                return ("left" if glued[0] == "l" else "right"), part[len(glued) :]
    return side, part


def _ancestors(j: int, parents: list[int]) -> list[int]:
    out = []
    while j >= 0:
        out.append(j)
        j = parents[j]
    return out


def _limb(parsed, side: str, roles: tuple[str, ...], parents: list[int]) -> dict[str, int]:
    """Role -> joint index for one limb: first alias with a joint, each joint used once, each below the last."""
    found: dict[str, int] = {}
    used: set[int] = set()
    for role in roles:
        for alias in LIMB_ALIASES[role]:
            hits = [i for i, (s, p) in enumerate(parsed) if s == side and p == alias and i not in used]
            prev = [found[r] for r in roles[: roles.index(role)] if r in found]
            hits = [i for i in hits if not prev or prev[-1] in _ancestors(i, parents)]
            if hits:
                found[role] = hits[0]
                used.add(hits[0])
                break
    if "shoulder" in roles and "shoulder" not in found and "collar" in found:
        if parsed[found["collar"]][1] == "shoulder":  # Shoulder/Elbow/Wrist without a clavicle joint
            found["shoulder"] = found.pop("collar")
    return found


def infer_smpl22(names: list[str], parents: list[int], offsets: np.ndarray | None = None) -> dict[str, list[str]]:
    """SMPL-22 joint -> source joint names (averaged). Raises ValueError naming every joint it cannot match."""
    parsed = [side_and_part(n) for n in names]
    zero = np.zeros(len(names), dtype=bool)
    if offsets is not None:
        lengths = np.linalg.norm(np.asarray(offsets, dtype=np.float64), axis=-1)
        zero = lengths <= 1e-4 * max(lengths.max(), 1e-12)
        zero[0] = False
    limbs = {(side, kind): _limb(parsed, side, roles, parents)
             for side in ("left", "right") for kind, roles in (("leg", LEG), ("arm", ARM))}  # fmt: skip
    out: dict[str, list[str]] = {}
    for (side, _), found in limbs.items():
        for role, j in found.items():
            out[f"{side[0]}_{role}"] = [names[j]]

    heads = [i for i, (s, p) in enumerate(parsed) if s is None and p == "head"]
    pelvis = _pelvis(parsed, parents, [limbs[(s, "leg")].get("hip") for s in ("left", "right")])
    out["pelvis"] = [names[pelvis]]
    if heads:
        out["head"] = [names[heads[0]]]
    # Without a Head joint the spine still ends at the first Neck joint.
    top = heads[0] if heads else next((i for i, (s, p) in enumerate(parsed) if s is None and "neck" in p), None)
    if top is not None:
        path = _ancestors(top, parents)
        path = path[: path.index(pelvis)][::-1] if pelvis in path else []  # pelvis (excl.) .. top (incl.)
        path = path[:-1] if heads else path
        necks = [i for i in path if "neck" in parsed[i][1]]
        spine = [i for i in path[: path.index(necks[0])] if not zero[i]] if necks else [i for i in path if not zero[i]]
        tops = [limbs[(s, "arm")].get("collar", limbs[(s, "arm")].get("shoulder")) for s in ("left", "right")]
        branch = next((parents[t] for t in tops if t is not None and parents[t] in spine), None)
        if branch is not None:
            spine = spine[: spine.index(branch) + 1]
        neck = next((i for i in necks if not zero[i]), necks[0] if necks else None)
        out.update(_spine(spine, names, pelvis))
        if neck is not None:
            out["neck"] = [names[neck]]
        elif "spine3" in out and heads:
            out["neck"] = out["spine3"] + out["head"]
    for s in ("l", "r"):
        shoulder, collar = out.get(f"{s}_shoulder"), out.get(f"{s}_collar")
        if shoulder and not collar and "spine3" in out:
            out[f"{s}_collar"] = out["spine3"] + shoulder
        elif shoulder and collar and zero[names.index(collar[0])]:
            out[f"{s}_collar"] = collar + shoulder
    missing = [j for j in SMPL22_NAMES if j not in out]
    if missing:
        raise ValueError(
            f"cannot tell which joints of this skeleton are SMPL's {', '.join(missing)} from the joint names "
            f"({', '.join(names)}). Rename them to a usual convention (e.g. LeftUpLeg/LeftLeg/LeftFoot/LeftToeBase, "
            f"Spine/Spine1, Neck, Head, LeftShoulder/LeftArm/LeftForeArm/LeftHand), or {HOW_TO_MAP}"
        )
    return {j: out[j] for j in SMPL22_NAMES}


def _pelvis(parsed, parents: list[int], hips: list[int | None]) -> int:
    """Where the legs meet (their lowest common ancestor); else a joint named Hips/Pelvis; else the root."""
    if all(h is not None for h in hips):
        left_up = _ancestors(parents[hips[0]], parents)
        return next(a for a in _ancestors(parents[hips[1]], parents) if a in left_up)
    return next((i for i, (s, p) in enumerate(parsed) if s is None and p in ("hips", "pelvis", "hip")), 0)


def _spine(spine: list[int], names: list[str], pelvis: int) -> dict[str, list[str]]:
    if not spine:
        return {}
    n = [names[i] for i in spine]
    if len(n) == 1:
        return {"spine1": [names[pelvis], n[0]], "spine2": n, "spine3": n}
    if len(n) == 2:
        return {"spine1": n[:1], "spine2": n, "spine3": n[1:]}
    middle = n[1:-1]
    k = len(middle)
    return {"spine1": n[:1], "spine2": middle[(k - 1) // 2 : k // 2 + 1], "spine3": n[-1:]}


def leg_length(names: list[str], parents: list[int], offsets: np.ndarray, joints: dict[str, list[str]]) -> float:
    """Mean hip-to-ankle length of the two legs in file units, along the rest offsets."""
    offsets = np.asarray(offsets, dtype=np.float64)
    total = []
    for s in ("l", "r"):
        hip, ankle = names.index(joints[f"{s}_hip"][0]), names.index(joints[f"{s}_ankle"][0])
        chain = _ancestors(ankle, parents)
        total.append(sum(np.linalg.norm(offsets[j]) for j in chain[: chain.index(hip)]))
    return float(np.mean(total))


def guess_units(names: list[str], parents: list[int], offsets: np.ndarray, joints: dict[str, list[str]]) -> float:
    """Factor to metres: the unit convention that makes the leg closest to an adult's 0.8 m (log scale)."""
    leg = leg_length(names, parents, offsets, joints)
    if not leg > 0:
        raise ValueError("cannot guess the units: the legs have zero length; pass units_to_metres")
    name, factor = min(UNITS.items(), key=lambda kv: abs(np.log(leg * kv[1] / LEG_METRES)))
    if not PLAUSIBLE_LEG[0] <= leg * factor <= PLAUSIBLE_LEG[1]:
        raise ValueError(
            f"cannot guess the units: a leg is {leg:g} units long, which is no adult's leg in "
            f"{', '.join(UNITS)}; pass units_to_metres (--units-to-metres)"
        )
    return factor
