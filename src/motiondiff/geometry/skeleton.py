"""Skeleton definitions: joint names, parents, rest offsets, feet, facing joints and body-part sets.

Three sources: the SMPL 22-joint layout of HumanML3D, the 21-joint KIT-ML layout, and any skeleton read from a BVH
file (parts inferred from joint names, see `Skeleton.infer`). Everything that needs to know "which joints are the
left arm" or "which joints touch the ground" asks a `Skeleton`; nothing else hard-codes joint indices.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np


@dataclass(frozen=True, eq=False)
class Skeleton:
    name: str
    joint_names: tuple[str, ...]
    parents: tuple[int, ...]  # -1 for the root
    offsets: np.ndarray  # (J, 3) rest offset of each joint from its parent
    foot_joints: tuple[tuple[int, ...], tuple[int, ...]]  # (left, right), used for foot contacts
    parts: dict[str, tuple[int, ...]] = field(default_factory=dict)  # body-part presets for editing
    # (right hip, left hip, right shoulder, left shoulder): defines the facing direction
    face_joints: tuple[int, int, int, int] | None = None
    # HumanML3D-style IK needs each joint's rest direction; for SMPL-22/KIT-21 these are axis-aligned unit vectors.
    raw_offsets: np.ndarray | None = None
    # Two joints whose bone lengths sum to the leg length that HumanML3D's uniform-skeleton step rescales by.
    leg_joints: tuple[int, int] | None = None
    fps: float | None = None
    # Chains as the dataset defines them (HumanML3D's IK walks these; each starts from the root rotation).
    chains: tuple[tuple[int, ...], ...] | None = None
    # What each leaf joint ends in, for the End Sites of exported BVH files ("head", "hand" or "toe", see
    # END_SITE_STATURE); None: read from the joint names (head/skull, hand/wrist/finger, toe/foot/ankle).
    leaf_roles: dict[int, str] | None = None

    def __post_init__(self):
        j = len(self.joint_names)
        if len(self.parents) != j or np.shape(self.offsets) != (j, 3):
            raise ValueError(f"skeleton {self.name!r}: names, parents and offsets disagree on the joint count")
        for i, p in enumerate(self.parents):
            if not (p == -1 and i == 0) and not (0 <= p < i):
                raise ValueError(f"skeleton {self.name!r}: joints must be ordered parents first (joint {i})")

    @property
    def num_joints(self) -> int:
        return len(self.joint_names)

    def index(self, joint: str | int) -> int:
        if isinstance(joint, int | np.integer):
            return int(joint)
        try:
            return self.joint_names.index(joint)
        except ValueError:
            raise KeyError(
                f"skeleton {self.name!r} has no joint {joint!r}; joints: {', '.join(self.joint_names)}"
            ) from None

    def part(self, name: str) -> tuple[int, ...]:
        """Joint indices of a body-part preset (e.g. 'lower_body', 'left_arm')."""
        if name not in self.parts:
            raise KeyError(f"unknown body part {name!r} for skeleton {self.name!r}; choose from {sorted(self.parts)}")
        return self.parts[name]

    @cached_property
    def mirror_permutation(self) -> tuple[int, ...]:
        """For each joint, its left/right counterpart (itself on the midline): mirroring a motion is negating x (the
        body's side axis in the canonical frame) and reading the joints through this permutation."""
        index = {n.lower(): i for i, n in enumerate(self.joint_names)}
        out = []
        for i, name in enumerate(self.joint_names):
            partner = None
            for a, b in _SIDE_SWAPS:
                swapped = re.sub(a, b, name.lower(), count=1)
                if swapped != name.lower() and swapped in index:
                    partner = index[swapped]
                    break
            out.append(i if partner is None else partner)
        return tuple(out)

    @cached_property
    def children(self) -> tuple[tuple[int, ...], ...]:
        kids: list[list[int]] = [[] for _ in self.parents]
        for i, p in enumerate(self.parents):
            if p >= 0:
                kids[p].append(i)
        return tuple(tuple(k) for k in kids)

    @cached_property
    def kinematic_chains(self) -> tuple[tuple[int, ...], ...]:
        """Chains to each leaf, for drawing and chain-wise IK: the dataset's own, else split at branching joints."""
        if self.chains is not None:
            return self.chains
        chains = []
        for start in [0] + [i for i, k in enumerate(self.children) if len(k) > 1 and i != 0]:
            for child in self.children[start]:
                chain = [start, child]
                while len(self.children[chain[-1]]) == 1:
                    chain.append(self.children[chain[-1]][0])
                chains.append(tuple(chain))
        return tuple(chains)

    @property
    def bone_lengths(self) -> np.ndarray:
        return np.linalg.norm(self.offsets, axis=-1)

    def with_offsets(self, offsets: np.ndarray) -> Skeleton:
        return _replace(self, offsets=np.asarray(offsets, dtype=np.float64))

    def stature(self, offsets: np.ndarray | None = None) -> float | None:
        """Standing height H (units of the offsets) estimated from the leg: hip to ankle is LEG_STATURE (0.491) H.
        The leg is the two bones of `leg_joints`, else the left leg's bones from its knee to its first foot joint;
        None for a skeleton without legs."""
        lengths = np.linalg.norm(np.asarray(self.offsets if offsets is None else offsets, dtype=np.float64), axis=-1)
        if self.leg_joints is not None:
            leg = float(lengths[list(self.leg_joints)].sum())
        else:
            limb, feet = self.parts.get("left_leg", ()), self.foot_joints[0]
            if len(limb) < 3 or not feet or feet[0] not in limb[1:]:
                return None
            leg = float(lengths[list(limb[1 : limb.index(feet[0]) + 1])].sum())
        return leg / LEG_STATURE if leg > 0 else None

    def end_sites(self, offsets: np.ndarray | None = None) -> dict[int, np.ndarray]:
        """End Site OFFSET (in the leaf's own frame) of every leaf joint, on rest `offsets` (default: the
        skeleton's): along the leaf's own bone (the bone continued past the joint; its parent's bone where the leaf's
        is zero, +Y where both are), as long as END_SITE_STATURE says for the leaf's role times `stature`; a leaf
        of no known role, or a skeleton without legs, continues its bone by the bone's own length. Never zero."""
        offsets = np.asarray(self.offsets if offsets is None else offsets, dtype=np.float64)
        lengths = np.linalg.norm(offsets, axis=-1)
        height = self.stature(offsets)
        scale = float(lengths.max()) if lengths.max() > 0 else 1.0
        sites = {}
        for leaf in (j for j, kids in enumerate(self.children) if not kids):
            bone = next((j for j in (leaf, self.parents[leaf]) if j >= 0 and lengths[j] > 1e-9 * scale), None)
            direction = offsets[bone] / lengths[bone] if bone is not None else np.array([0.0, 1.0, 0.0])
            name = self.joint_names[leaf]
            role = self.leaf_roles.get(leaf) if self.leaf_roles is not None else _leaf_role(name)
            if role in END_SITE_STATURE and height is not None:
                length = END_SITE_STATURE[role] * height
            else:
                length = lengths[bone] if bone is not None else 0.1 * scale
            sites[leaf] = direction * length
        return sites

    # ---- any skeleton (BVH) --------------------------------------------------------------------------------
    @classmethod
    def infer(cls, name: str, joint_names, parents, offsets, fps: float | None = None) -> Skeleton:
        """Build a skeleton from names and topology, inferring sides, limbs and feet from the joint names.

        Works for the usual mocap naming schemes (Bandai 'UpperLeg_L', CMU/Mixamo 'LeftUpLeg', ASF-style
        'lfemur'). Joints whose role cannot be read from the name count as torso.
        """
        joint_names = tuple(joint_names)
        roles = [_joint_role(n) for n in joint_names]
        sides = [_joint_side(n) for n in joint_names]
        parents = tuple(int(p) for p in parents)
        # A limb role propagates to descendants (fingers under a hand, toes under a foot).
        for i, p in enumerate(parents):
            if p >= 0 and roles[i] in ("torso", "head") and roles[p] in ("arm", "leg"):
                roles[i] = roles[p]
            if p >= 0 and sides[i] is None and roles[i] in ("arm", "leg"):
                sides[i] = sides[p]
        limb = {
            (role, side): tuple(i for i in range(len(joint_names)) if roles[i] == role and sides[i] == side)
            for role in ("arm", "leg")
            for side in ("left", "right")
        }
        feet = tuple(
            tuple(i for i in limb[("leg", side)] if re.search(r"foot|ankle|toe", joint_names[i], re.I))
            for side in ("left", "right")
        )
        torso = tuple(i for i in range(len(joint_names)) if roles[i] == "torso")
        head = tuple(i for i in range(len(joint_names)) if roles[i] == "head")
        parts = _standard_parts(
            root=0,
            torso=torso,
            head=head,
            left_arm=limb[("arm", "left")],
            right_arm=limb[("arm", "right")],
            left_leg=limb[("leg", "left")],
            right_leg=limb[("leg", "right")],
        )
        face = None
        if all(limb[k] for k in limb):
            face = tuple(_first_matching(limb[("leg", s)], joint_names, _UPPER_LEG) for s in ("right", "left"))
            face += tuple(_first_matching(limb[("arm", s)], joint_names, _UPPER_ARM) for s in ("right", "left"))
        return cls(
            name=name,
            joint_names=joint_names,
            parents=parents,
            offsets=np.asarray(offsets, dtype=np.float64),
            foot_joints=feet,  # type: ignore[arg-type]
            parts=parts,
            face_joints=face,  # type: ignore[arg-type]
            fps=fps,
        )


# ---- End Sites -------------------------------------------------------------------------------------------------
# Where the body goes on past a leaf joint (the tip a BVH End Site marks: animation tools draw the leaf's bone up to
# it), as fractions of the standing height H. From Drillis & Contini's segment lengths as fractions of H (tabulated in
# D. A. Winter, Biomechanics and Motor Control of Human Movement, Fig. 4.1): the hand, wrist to fingertip, 0.108 H;
# the foot 0.152 H, about 0.27 of it ahead of the ball of the foot where the toe joints (SMPL's l_foot/r_foot,
# Bandai's Toes) sit: 0.041 H; the head, chin to vertex, 0.130 H, of which the half above the head joint (SMPL's
# head joint sits about mid-head): 0.065 H. H comes from the leg (`Skeleton.stature`): hip (0.530 H) to ankle
# (0.039 H) is 0.491 H. On HumanML3D's target skeleton (leg 0.816 m, H 1.66 m) the tips are 0.18, 0.07, 0.11 m.
END_SITE_STATURE = {"hand": 0.108, "toe": 0.041, "head": 0.065}
LEG_STATURE = 0.491
_LEAF_ROLES = (("hand", re.compile(r"hand|wrist|finger|thumb|palm", re.I)),
               ("toe", re.compile(r"toe|foot|ankle|ball", re.I)),
               ("head", re.compile(r"head|skull|top", re.I)))  # fmt: skip


def _leaf_role(name: str) -> str | None:
    return next((role for role, pattern in _LEAF_ROLES if pattern.search(name)), None)


def _replace(skel: Skeleton, **changes) -> Skeleton:
    from dataclasses import replace

    return replace(skel, **changes)


def _tokens(name: str) -> list[str]:
    spaced = re.sub(r"([a-z0-9])([A-Z])", r"\1 \2", name)
    return [t.lower() for t in re.split(r"[^A-Za-z0-9]+", spaced) if t]


_LEG = re.compile(r"upleg|thigh|femur|leg|knee|shin|calf|tibia|ankle|foot|toe|hipjoint")
_ARM = re.compile(r"shoulder|clavicle|collar|arm|humerus|elbow|radius|wrist|hand|finger|thumb|index|middle|ring|pinky")
_HEAD = re.compile(r"neck|head|skull|jaw|eye")


def _joint_role(name: str) -> str:
    low = name.lower()
    if _LEG.search(low) or (re.fullmatch(r"[lr]_?hip", low) or re.search(r"(left|right)_?hip", low)):
        return "leg"
    if _ARM.search(low):
        return "arm"
    if _HEAD.search(low):
        return "head"
    return "torso"


# Name patterns of a joint's other side: l_hip/r_hip, LeftArm/RightArm, KIT's LS/RS, ASF's lfemur/rfemur.
_SIDE_SWAPS = ((r"left", "right"), (r"right", "left"), (r"^l", "r"), (r"^r", "l"), (r"_l(?=$|_)", "_r"),
               (r"_r(?=$|_)", "_l"))  # fmt: skip


def _joint_side(name: str) -> str | None:
    tokens = _tokens(name)
    if {"l", "left"} & set(tokens):
        return "left"
    if {"r", "right"} & set(tokens):
        return "right"
    low = name.lower()
    # ASF-style names glue the side on: 'lfemur', 'rhumerus', 'lhipjoint'.
    if len(low) > 2 and low[0] in "lr" and (_LEG.match(low[1:]) or _ARM.match(low[1:]) or low[1:] == "hipjoint"):
        return "left" if low[0] == "l" else "right"
    return None


# The joints that set hip and shoulder width (not the CMU 'LHipJoint' at the pelvis, not the clavicle).
_UPPER_LEG = re.compile(r"up_?per_?leg|upleg|thigh|femur|hip(?!joint)", re.I)
_UPPER_ARM = re.compile(r"up_?per_?arm|uparm|humerus|(^|[^a-z])arm$|(left|right)arm$", re.I)


def _first_matching(limb: tuple[int, ...], names: tuple[str, ...], pattern: re.Pattern) -> int:
    for i in limb:
        if pattern.search(names[i]):
            return i
    return limb[1] if len(limb) > 2 else limb[0]


def _standard_parts(root, torso, head, left_arm, right_arm, left_leg, right_leg) -> dict[str, tuple[int, ...]]:
    """Body-part presets shared by every skeleton (MDM's lower body = root + legs; upper = the rest)."""
    lower = tuple(sorted({root, *left_leg, *right_leg}))
    upper = tuple(sorted((set(torso) | set(head) | set(left_arm) | set(right_arm)) - {root}))
    return {
        "lower_body": lower,
        "upper_body": upper,
        "left_arm": tuple(left_arm),
        "right_arm": tuple(right_arm),
        "arms": tuple(sorted({*left_arm, *right_arm})),
        "left_leg": tuple(left_leg),
        "right_leg": tuple(right_leg),
        "legs": tuple(sorted({*left_leg, *right_leg})),
        "torso": tuple(sorted(set(torso) - {root})),
        "head": tuple(head),
        "root": (root,),
    }


def _from_chains(num_joints: int, chains) -> tuple[int, ...]:
    parents = [-1] * num_joints
    for chain in chains:
        for a, b in zip(chain[:-1], chain[1:], strict=True):
            parents[b] = a
    return tuple(parents)


# ---- SMPL 22 joints (HumanML3D) -------------------------------------------------------------------------------
SMPL22_NAMES = (
    "pelvis", "l_hip", "r_hip", "spine1", "l_knee", "r_knee", "spine2", "l_ankle", "r_ankle", "spine3",
    "l_foot", "r_foot", "neck", "l_collar", "r_collar", "head", "l_shoulder", "r_shoulder", "l_elbow",
    "r_elbow", "l_wrist", "r_wrist",
)  # fmt: skip
SMPL22_CHAINS = (
    (0, 2, 5, 8, 11),
    (0, 1, 4, 7, 10),
    (0, 3, 6, 9, 12, 15),
    (9, 14, 17, 19, 21),
    (9, 13, 16, 18, 20),
)
# Rest direction of each joint's bone in HumanML3D's IK (x left, y up, z forward).
SMPL22_RAW_OFFSETS = np.array(
    [[0, 0, 0], [1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, -1, 0], [0, 1, 0], [0, -1, 0], [0, -1, 0],
     [0, 1, 0], [0, 0, 1], [0, 0, 1], [0, 1, 0], [1, 0, 0], [-1, 0, 0], [0, 0, 1], [0, -1, 0], [0, -1, 0],
     [0, -1, 0], [0, -1, 0], [0, -1, 0], [0, -1, 0]],
    dtype=np.float64,
)  # fmt: skip
# HumanML3D's target skeleton: bone lengths (m) of joints 1..21. The official pipeline retargets every clip to the
# skeleton of its motion 000021; these are the lengths measured on the official sample new_joints/012314 (constant
# to 1e-6 over its frames). The 4-digit values of the procedure notes are too coarse to reproduce features to 1e-4.
SMPL22_BONE_LENGTHS = np.array(
    [0.0, 0.10307397, 0.10988336, 0.13156823, 0.39362319, 0.39018822, 0.14319022, 0.43243300, 0.42564340,
     0.05736474, 0.14338179, 0.14941905, 0.21936005, 0.13748679, 0.14338281, 0.10303921, 0.13161396, 0.12298439,
     0.25683990, 0.26309186, 0.26601182, 0.26987629]
)  # fmt: skip

SMPL22 = Skeleton(
    name="smpl22",
    joint_names=SMPL22_NAMES,
    parents=_from_chains(22, SMPL22_CHAINS),
    offsets=SMPL22_RAW_OFFSETS * SMPL22_BONE_LENGTHS[:, None],
    foot_joints=((7, 10), (8, 11)),
    parts=_standard_parts(
        root=0,
        torso=(3, 6, 9),
        head=(12, 15),
        left_arm=(13, 16, 18, 20),
        right_arm=(14, 17, 19, 21),
        left_leg=(1, 4, 7, 10),
        right_leg=(2, 5, 8, 11),
    ),  # fmt: skip
    face_joints=(2, 1, 17, 16),
    raw_offsets=SMPL22_RAW_OFFSETS,
    leg_joints=(5, 8),
    fps=20.0,
    chains=SMPL22_CHAINS,
    leaf_roles={15: "head", 10: "toe", 11: "toe", 20: "hand", 21: "hand"},
)

# ---- KIT-ML 21 joints (MMM model) -----------------------------------------------------------------------------
KIT21_NAMES = (
    "root", "BP", "BT", "BLN", "BUN", "RS", "RE", "RW", "LS", "LE", "LW",
    "RH", "RK", "RA", "RMrot", "RF", "LH", "LK", "LA", "LMrot", "LF",
)  # fmt: skip
KIT21_CHAINS = (
    (0, 11, 12, 13, 14, 15),
    (0, 16, 17, 18, 19, 20),
    (0, 1, 2, 3, 4),
    (3, 5, 6, 7),
    (3, 8, 9, 10),
)
KIT21_RAW_OFFSETS = np.array(
    [[0, 0, 0], [0, 1, 0], [0, 1, 0], [0, 1, 0], [0, 1, 0], [1, 0, 0], [0, -1, 0], [0, -1, 0], [-1, 0, 0],
     [0, -1, 0], [0, -1, 0], [1, 0, 0], [0, -1, 0], [0, -1, 0], [0, 0, 1], [0, 0, 1], [-1, 0, 0], [0, -1, 0],
     [0, -1, 0], [0, 0, 1], [0, 0, 1]],
    dtype=np.float64,
)  # fmt: skip

KIT21 = Skeleton(
    name="kit21",
    joint_names=KIT21_NAMES,
    parents=_from_chains(21, KIT21_CHAINS),
    # KIT-ML's target bone lengths come from its motion 03950 (not shipped here); unit bones until a user's data
    # supplies them (`features_from_joints` then keeps the input's own bone lengths).
    offsets=KIT21_RAW_OFFSETS.copy(),
    foot_joints=((19, 20), (14, 15)),
    parts=_standard_parts(
        root=0,
        torso=(1, 2),
        head=(3, 4),
        left_arm=(8, 9, 10),
        right_arm=(5, 6, 7),
        left_leg=(16, 17, 18, 19, 20),
        right_leg=(11, 12, 13, 14, 15),
    ),  # fmt: skip
    face_joints=(11, 16, 5, 8),
    raw_offsets=KIT21_RAW_OFFSETS,
    leg_joints=(17, 18),
    fps=12.5,
    chains=KIT21_CHAINS,
    leaf_roles={4: "head", 7: "hand", 10: "hand", 15: "toe", 20: "toe"},
)

# ---- SMPL 24 joints (the SMPL body model's rig: HumanAct12, UESTC) ------------------------------------------------
# The first 22 joints are SMPL-22, so rig positions map to the feature skeleton by truncation.
SMPL24_NAMES = SMPL22_NAMES + ("l_hand", "r_hand")
# Approximate rest offsets of the SMPL neutral template (metres; x body-left, y up, z forward), rounded from the
# values EDGE publishes for its fixed SMPL skeleton. The SMPL model itself is licensed and not shipped; datasets
# replace these with offsets recovered from their own joints (see motiondiff.data.sources.smpl_clips).
SMPL24_REST_OFFSETS = np.array(
    [[0.0, 0.0, 0.0], [0.0586, -0.0823, -0.0177], [-0.0603, -0.0905, -0.0135], [0.0044, 0.1244, -0.0384],
     [0.0435, -0.3865, 0.0080], [-0.0433, -0.3837, -0.0048], [0.0045, 0.1380, 0.0268], [-0.0148, -0.4269, -0.0374],
     [0.0191, -0.4200, -0.0346], [-0.0023, 0.0560, 0.0029], [0.0411, -0.0603, 0.1220], [-0.0348, -0.0621, 0.1303],
     [-0.0134, 0.2116, -0.0335], [0.0717, 0.1140, -0.0189], [-0.0830, 0.1125, -0.0237], [0.0101, 0.0889, 0.0504],
     [0.1229, 0.0452, -0.0190], [-0.1132, 0.0469, -0.0085], [0.2553, -0.0156, -0.0229], [-0.2601, -0.0144, -0.0313],
     [0.2657, 0.0127, -0.0074], [-0.2691, 0.0068, -0.0060], [0.0867, -0.0106, -0.0156], [-0.0888, -0.0087, -0.0101]]
)  # fmt: skip

SMPL24 = Skeleton(
    name="smpl24",
    joint_names=SMPL24_NAMES,
    parents=(-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21),
    offsets=SMPL24_REST_OFFSETS,
    foot_joints=((7, 10), (8, 11)),
    parts=_standard_parts(
        root=0,
        torso=(3, 6, 9),
        head=(12, 15),
        left_arm=(13, 16, 18, 20, 22),
        right_arm=(14, 17, 19, 21, 23),
        left_leg=(1, 4, 7, 10),
        right_leg=(2, 5, 8, 11),
    ),  # fmt: skip
    face_joints=(2, 1, 17, 16),
    leg_joints=(5, 8),
    fps=20.0,
)

SKELETONS = {"smpl22": SMPL22, "kit21": KIT21, "smpl24": SMPL24}


def get_skeleton(name: str) -> Skeleton:
    if name not in SKELETONS:
        raise KeyError(f"unknown skeleton {name!r}; choose from {sorted(SKELETONS)} or build one with Skeleton.infer")
    return SKELETONS[name]
