"""A mannequin: a low-poly body of capsules made in code from any skeleton, so the videos (render=body) and the
FBX/GLB files show a body without the licence-restricted SMPL model.

Each piece is a capsule (a tube tapered from one radius to the other, closed by two half-spheres) between two points
of the skeleton: a bone (a joint and its child), a hand or foot (a leaf joint and the tip its End Site marks), the
pelvis (from hip to hip) and the chest (from one arm's first joint to the other's); the head is a ball about the
head joint, its top at the head's End Site. Sizes are fractions of the standing height H (`Skeleton.stature`): a
limb tapers by the distance from its tip, so an arm with or without a collar joint gets the same shoulder. The
fractions are round numbers for a slim adult, chosen to look like one (a mannequin, not a measured body).

A capsule is round about its axis, so it is placed by its two end points alone: `Mannequin.at` poses the mesh from
joint positions (no IK; a bone that stretches stretches its piece), turning each piece's rest ring by the shortest
arc onto its posed axis. Each vertex moves with one joint (rigid skinning, weight 1): the joint whose rotation
carries the piece's end points (a bone's parent, the leaf of a hand, foot or head, the common parent of the hips or
of the shoulders), which is how the FBX/GLB armature binds the mesh.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from motiondiff.geometry.kinematics import forward_kinematics
from motiondiff.geometry.rotations import any_perpendicular, qrot, qswing
from motiondiff.geometry.skeleton import Skeleton

# Radii as fractions of the standing height H. Limbs: (distance from the limb's tip, radius), both in H, interpolated.
ARM_RADII = ((0.0, 0.012), (0.108, 0.018), (0.27, 0.024), (0.42, 0.032), (0.5, 0.04))  # tip, wrist, elbow, shoulder
LEG_RADII = ((0.0, 0.016), (0.04, 0.02), (0.13, 0.024), (0.39, 0.033), (0.62, 0.05))  # toe tip, ball, ankle, knee, hip
TORSO_RADIUS = 0.07  # spine joints: a round trunk 0.23 m across for H = 1.66 m
NECK_RADIUS = 0.03
HEAD_RADIUS = 0.06
PELVIS_RADIUS = 0.05  # the capsule from hip to hip
CHEST_RADIUS = 0.045  # the capsule from shoulder to shoulder
OTHER_RADIUS = 0.03  # joints of no known part (a skeleton whose names tell nothing)
SEGMENTS = 10  # vertices around a ring: low-poly on purpose
CAP_ANGLES = (60.0, 30.0, 0.0)  # degrees of latitude of a half-sphere's rings, from near the pole to the equator
_TINY = 1e-9


@dataclass(frozen=True, eq=False)
class Mannequin:
    """The mesh of a `skeleton` (whose offsets it was sized on): triangles `faces` (F, 3), wound counter-clockwise
    seen from outside, and for each vertex the joint it moves with (`owners` (V,)). Each piece p runs from end point
    A to B, each end a joint plus a length along a bone: ``joint[p, e] + reach[p, e] * unit(joint - toward[p, e])``
    (toward -1: the joint itself); its axis is unit(axis_to - axis_from). A vertex of piece `piece` sits at A + t
    (B - A) + along * axis + the rest ring vector `ring` turned onto the posed axis."""

    skeleton: Skeleton
    faces: np.ndarray
    owners: np.ndarray
    piece: np.ndarray  # (V,) the piece each vertex belongs to
    t: np.ndarray  # (V,) 0 on A's half-sphere, 1 on B's
    along: np.ndarray  # (V,) distance (the offsets' units) along the axis past A (< 0) or B (> 0)
    ring: np.ndarray  # (V, 3) the vertex's offset from the axis, in the rest pose
    joint: np.ndarray  # (P, 2) the joint of each end point
    toward: np.ndarray  # (P, 2) the joint whose bone the end point continues (-1: none)
    reach: np.ndarray  # (P, 2) distance beyond the joint along that bone
    axis_from: np.ndarray  # (P,)
    axis_to: np.ndarray  # (P,)
    rest_axis: np.ndarray  # (P, 3) unit axes in the rest pose

    @property
    def num_vertices(self) -> int:
        return len(self.owners)

    @property
    def weights(self) -> np.ndarray:
        """(V, J) skinning weights: 1 on each vertex's owner joint."""
        out = np.zeros((self.num_vertices, self.skeleton.num_joints))
        out[np.arange(self.num_vertices), self.owners] = 1.0
        return out

    def rest_positions(self) -> np.ndarray:
        """(J, 3) joints of the rest pose: offsets summed down the tree from the root's offset."""
        offsets = np.asarray(self.skeleton.offsets, dtype=np.float64)
        identity = np.zeros((len(offsets), 4))
        identity[:, 0] = 1.0
        return forward_kinematics(identity, offsets, self.skeleton.parents)[0]

    def rest_vertices(self) -> np.ndarray:
        """(V, 3) the mesh in the rest pose (what an armature binds)."""
        return self.at(self.rest_positions()[None])[0]

    def at(self, joints: np.ndarray) -> np.ndarray:
        """Vertices (N, V, 3) of the mesh posed by joints (N, J, 3) of its skeleton (any units, the offsets')."""
        joints = np.asarray(joints, dtype=np.float64)
        if joints.ndim != 3 or joints.shape[1:] != (self.skeleton.num_joints, 3) or not np.isfinite(joints).all():
            raise ValueError(f"mannequin of {self.skeleton.name!r}: joints must be finite with shape (frames, "
                             f"{self.skeleton.num_joints}, 3), got {joints.shape}")  # fmt: skip
        ends = [self._end(joints, e) for e in (0, 1)]  # (N, P, 3) each
        axis = joints[:, self.axis_to] - joints[:, self.axis_from]
        length = np.linalg.norm(axis, axis=-1, keepdims=True)
        axis = np.where(length > _TINY, axis / np.maximum(length, _TINY), self.rest_axis)
        turn = qswing(np.broadcast_to(self.rest_axis, axis.shape), axis)  # (N, P, 4): rest axis -> posed axis
        p, t = self.piece, self.t[None, :, None]
        centre = ends[0][:, p] + t * (ends[1][:, p] - ends[0][:, p]) + self.along[None, :, None] * axis[:, p]
        return centre + qrot(turn[:, p], np.broadcast_to(self.ring, centre.shape))

    def posed(self, rotations: np.ndarray, root: np.ndarray) -> np.ndarray:
        """Vertices (N, V, 3) for local joint rotations (N, J, 4) (w, x, y, z; as a BVH holds them) and root positions
        (N, 3) on the mannequin's offsets, skinned as an armature skins them: each rest vertex carried by its owner
        joint's world transform. With leaves at rest rotation (as IK leaves them) this is `at` of the posed joints up
        to a turn of each ring about its axis; a turned leaf turns its hand, foot or head."""
        rotations = np.asarray(rotations, dtype=np.float64)
        translations = np.repeat(np.asarray(self.skeleton.offsets, dtype=np.float64)[None], len(rotations), axis=0)
        translations[:, 0] = root
        joints, world = forward_kinematics(rotations, translations, self.skeleton.parents)
        rest = self.rest_vertices() - self.rest_positions()[self.owners]
        return joints[:, self.owners] + qrot(world[:, self.owners], np.broadcast_to(rest, (len(joints), *rest.shape)))

    def _end(self, joints: np.ndarray, e: int) -> np.ndarray:
        at = joints[:, self.joint[:, e]]
        toward = self.toward[:, e]
        bone = at - joints[:, np.maximum(toward, 0)]
        length = np.linalg.norm(bone, axis=-1, keepdims=True)
        step = np.where((toward >= 0)[:, None] & (length > _TINY), bone / np.maximum(length, _TINY), 0.0)
        return at + self.reach[:, e, None] * step


def build_mannequin(skeleton: Skeleton, offsets: np.ndarray | None = None) -> Mannequin:
    """The mannequin of `skeleton` sized on `offsets` (J, 3) (default: the skeleton's; a motion's own bone lengths:
    `inverse_kinematics.fit_rest_offsets`). Pieces: every bone of non-zero length below the pelvis (the joint the
    legs hang from; a ground-level root above it, as Bandai's, gets none), the hands and feet to their End Site
    tips, the head, the pelvis and the chest (in place of the bones from their middle joint to the limbs they join;
    module doc)."""
    skeleton = skeleton.with_offsets(np.asarray(skeleton.offsets if offsets is None else offsets, dtype=np.float64))
    offsets = skeleton.offsets
    lengths = np.linalg.norm(offsets, axis=-1)
    height = _height(skeleton)
    sites = skeleton.end_sites()
    roles = _roles(skeleton)
    radius = _joint_radii(skeleton, height, roles, sites)
    above = _above_pelvis(skeleton)
    pieces: list[tuple] = []  # (A, B, axis pair, radius A, radius B, owner, sphere)
    covered = set()  # limbs' first joints joined by the pelvis or chest: the bones to them lie inside it
    for left, right, r in (("left_leg", "right_leg", PELVIS_RADIUS), ("left_arm", "right_arm", CHEST_RADIUS)):
        a, b = skeleton.parts.get(right, ()), skeleton.parts.get(left, ())
        if a and b and skeleton.parents[a[0]] == skeleton.parents[b[0]] >= 0:
            pieces.append(((a[0], -1, 0.0), (b[0], -1, 0.0), (a[0], b[0]), r * height, r * height,
                           skeleton.parents[a[0]], False))  # fmt: skip
            covered |= {a[0], b[0]}
    for child, parent in enumerate(skeleton.parents):
        if parent < 0 or parent in above or child in covered or lengths[child] <= _TINY * height:
            continue
        same_part = roles[parent] == roles[child] or (roles[child] in ("torso", "head") and roles[parent] == "torso")
        pieces.append(((parent, -1, 0.0), (child, -1, 0.0), (parent, child),
                       radius[parent] if same_part else radius[child], radius[child], parent, False))  # fmt: skip
    for leaf, site in sites.items():
        bone = next((j for j in (leaf, skeleton.parents[leaf]) if j > 0 and lengths[j] > _TINY * height), None)
        if bone is None or leaf in above:
            continue
        toward = skeleton.parents[bone]
        role = skeleton.leaf_roles.get(leaf) if skeleton.leaf_roles is not None else roles[leaf]
        if role == "head":
            centre = (leaf, toward, float(np.linalg.norm(site)) - HEAD_RADIUS * height)
            pieces.append((centre, centre, (toward, bone), HEAD_RADIUS * height, HEAD_RADIUS * height, leaf, True))
        else:
            tip = (leaf, toward, float(np.linalg.norm(site)))
            tip_radius = _limb_radius(roles[leaf], 0.0) * height
            pieces.append(((leaf, -1, 0.0), tip, (toward, bone), radius[leaf], tip_radius, leaf, False))
    if not pieces:
        raise ValueError(f"skeleton {skeleton.name!r} has no bone of non-zero length to build a mannequin on")
    return _assemble(skeleton, pieces)


def _assemble(skeleton: Skeleton, pieces: list[tuple]) -> Mannequin:
    """Vertices and triangles of every piece, and the arrays `Mannequin.at` places them by."""
    rest = forward_kinematics(np.tile([1.0, 0.0, 0.0, 0.0], (skeleton.num_joints, 1)), skeleton.offsets,
                              skeleton.parents)[0]  # fmt: skip
    angle = 2 * np.pi * np.arange(SEGMENTS) / SEGMENTS
    columns: dict[str, list] = {k: [] for k in ("owners", "piece", "t", "along", "ring", "faces")}
    count = 0
    for p, (_, _, (u0, u1), r_a, r_b, owner, sphere) in enumerate(pieces):
        axis = rest[u1] - rest[u0]
        axis = axis / np.linalg.norm(axis)
        e1 = any_perpendicular(axis)
        e2 = np.cross(axis, e1)
        circle = np.cos(angle)[:, None] * e1 + np.sin(angle)[:, None] * e2  # counter-clockwise seen from +axis
        lat = np.radians(CAP_ANGLES)
        # rings from A's pole to B's: (t, along, ring radius); a sphere has one equator
        rings = [(0.0, -r_a * np.sin(a), r_a * np.cos(a)) for a in lat]
        rings += [(1.0, r_b * np.sin(a), r_b * np.cos(a)) for a in lat[::-1][1 if sphere else 0 :]]
        t = [0.0] + [r[0] for r in rings for _ in angle] + [1.0]
        along = [-r_a] + [r[1] for r in rings for _ in angle] + [r_b]
        ring = [np.zeros(3)] + [r[2] * c for r in rings for c in circle] + [np.zeros(3)]
        n = len(t)
        index = (count + 1 + np.arange(len(rings))[:, None] * SEGMENTS + np.arange(SEGMENTS)[None]).astype(np.int64)
        nxt = np.roll(index, -1, axis=1)
        faces = [np.stack([np.full(SEGMENTS, count), nxt[0], index[0]], axis=1)]  # A's pole fan
        for i in range(len(rings) - 1):
            a, b, c, d = index[i], nxt[i], nxt[i + 1], index[i + 1]
            faces += [np.stack([a, b, c], axis=1), np.stack([a, c, d], axis=1)]
        faces.append(np.stack([np.full(SEGMENTS, count + n - 1), index[-1], nxt[-1]], axis=1))  # B's pole fan
        columns["faces"] += faces
        columns["owners"] += [owner] * n
        columns["piece"] += [p] * n
        columns["t"] += t
        columns["along"] += along
        columns["ring"] += ring
        count += n
    ends = [(a, b) for a, b, *_ in pieces]
    axes = np.array([pair for _, _, pair, *_ in pieces], dtype=np.int64)
    rest_axis = rest[axes[:, 1]] - rest[axes[:, 0]]
    return Mannequin(
        skeleton=skeleton,
        faces=np.concatenate(columns["faces"]).astype(np.int64),
        owners=np.asarray(columns["owners"], dtype=np.int64),
        piece=np.asarray(columns["piece"], dtype=np.int64),
        t=np.asarray(columns["t"], dtype=np.float64),
        along=np.asarray(columns["along"], dtype=np.float64),
        ring=np.asarray(columns["ring"], dtype=np.float64),
        joint=np.array([[e[0] for e in pair] for pair in ends], dtype=np.int64),
        toward=np.array([[e[1] for e in pair] for pair in ends], dtype=np.int64),
        reach=np.array([[e[2] for e in pair] for pair in ends], dtype=np.float64),
        axis_from=axes[:, 0],
        axis_to=axes[:, 1],
        rest_axis=rest_axis / np.linalg.norm(rest_axis, axis=-1, keepdims=True),
    )


def _height(skeleton: Skeleton) -> float:
    """Standing height H in the offsets' units: `Skeleton.stature`, else (no legs) the longest root-to-leaf path as
    a leg's share of H (0.6)."""
    height = skeleton.stature()
    if height:
        return height
    lengths = np.linalg.norm(skeleton.offsets, axis=-1)
    depth = np.zeros(skeleton.num_joints)
    for j, p in enumerate(skeleton.parents):
        depth[j] = depth[p] + lengths[j] if p >= 0 else 0.0
    return float(depth.max()) / 0.6 if depth.max() > 0 else 1.0


def _roles(skeleton: Skeleton) -> list[str]:
    """'arm', 'leg', 'head', 'torso' (the pelvis and spine of a skeleton with legs) or 'other' for each joint."""
    parts = skeleton.parts
    roles = ["other"] * skeleton.num_joints
    has_legs = bool(parts.get("left_leg") or parts.get("right_leg"))
    for name, role in (("torso", "torso"), ("root", "torso"), ("head", "head"), ("arms", "arm"), ("legs", "leg")):
        for j in parts.get(name, ()):
            roles[j] = role if (role != "torso" or has_legs) else "other"
    if has_legs:
        for j in _above_pelvis(skeleton) | {_pelvis(skeleton)}:
            roles[j] = "torso"
    return roles


def _pelvis(skeleton: Skeleton) -> int:
    """The joint the legs hang from (the root where there are no two legs of one parent)."""
    left, right = skeleton.parts.get("left_leg", ()), skeleton.parts.get("right_leg", ())
    if left and right and skeleton.parents[left[0]] == skeleton.parents[right[0]] >= 0:
        return skeleton.parents[left[0]]
    return 0


def _above_pelvis(skeleton: Skeleton) -> set[int]:
    """The pelvis's ancestors (a ground-level root above the hips): no piece hangs from them."""
    out, j = set(), skeleton.parents[_pelvis(skeleton)]
    while j >= 0:
        out.add(j)
        j = skeleton.parents[j]
    return out


def _limb_radius(role: str, distance: float) -> float:
    table = ARM_RADII if role == "arm" else LEG_RADII if role == "leg" else None
    if table is None:
        return OTHER_RADIUS
    return float(np.interp(distance, [d for d, _ in table], [r for _, r in table]))


def _joint_radii(skeleton: Skeleton, height: float, roles: list[str], sites: dict) -> np.ndarray:
    """Each joint's radius (offsets' units): limbs by their distance from the limb's farthest tip, the trunk, neck
    and the rest by role."""
    lengths = np.linalg.norm(skeleton.offsets, axis=-1)
    to_tip = np.zeros(skeleton.num_joints)  # distance down the limb to its farthest tip (End Site included)
    for j in reversed(range(skeleton.num_joints)):
        kids = [c for c in skeleton.children[j] if roles[c] == roles[j]]
        to_tip[j] = max([to_tip[c] + lengths[c] for c in kids], default=float(np.linalg.norm(sites.get(j, 0.0))))
    fixed = {"torso": TORSO_RADIUS, "head": NECK_RADIUS, "other": OTHER_RADIUS}
    return np.array([(fixed[r] if r in fixed else _limb_radius(r, to_tip[j] / height)) * height
                     for j, r in enumerate(roles)])  # fmt: skip
