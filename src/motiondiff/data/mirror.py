"""Left-right mirroring of training clips, as HumanML3D doubles its data with `M` copies.

A mirrored clip is the reflection x -> -x of the motion in its canonical frame (x is the body's side axis), with the
left and right joints exchanged, the caption's "left" and "right" exchanged and the action label replaced by its
mirror image (walk-left <-> walk-right, wave-left-hand <-> wave-right-hand). On HumanML3D/KIT-ML features the
reflection is a signed permutation of the feature dims (`mirror_hml_features`), so mirroring costs no feature
extraction and is exact: the mirrored features decode to the reflected joints, and mirroring twice is the identity.
"""

from __future__ import annotations

import re
from dataclasses import replace
from functools import cache

import numpy as np

from motiondiff.data.datasets import NO_ACTION, MotionRecord
from motiondiff.data.representations.hml_features import feature_dim, feature_slices, skeleton_for_dim
from motiondiff.geometry.skeleton import Skeleton

MIRROR_ID_PREFIX = "M"  # HumanML3D names the mirror of 000021 M000021
_SIDE = re.compile(r"(?<![a-z])(left|right)(?![a-z])", re.IGNORECASE)
_OTHER_SIDE = {"left": "right", "right": "left"}
# A rotation matrix R of the original becomes M R M with M = diag(-1, 1, 1): entry (i, j) changes sign by s_i s_j,
# s = (-1, 1, 1). The 6D layout is (R00, R10, R20, R01, R11, R21) (motiondiff.geometry.rotations.matrix_to_6d).
_SIX_D_SIGNS = np.array([1.0, -1.0, -1.0, -1.0, 1.0, 1.0])


def swap_left_right(text: str) -> str:
    """The text with every word 'left' and 'right' exchanged, keeping its case ('Left' -> 'Right')."""

    def other(match: re.Match) -> str:
        word = match.group(1)
        swapped = _OTHER_SIDE[word.lower()]
        if word.isupper():
            return swapped.upper()
        return swapped.capitalize() if word[0].isupper() else swapped

    return _SIDE.sub(other, text)


def mirrored_labels(names: list[str]) -> list[int]:
    """Index of each label's mirror image: the name with left/right swapped when the dataset has it, else itself."""
    index = {n: i for i, n in enumerate(names)}
    return [index.get(swap_left_right(n), i) for i, n in enumerate(names)]


@cache
def _signed_permutation(dim: int) -> tuple[np.ndarray, np.ndarray]:
    """(source index, sign) per feature dim: mirrored[..., d] = sign[d] * features[..., source[d]]."""
    return signed_permutation(skeleton_for_dim(dim))


def signed_permutation(skeleton: Skeleton) -> tuple[np.ndarray, np.ndarray]:
    """The mirror as (source index, sign) per dim of `skeleton`'s HumanML3D features."""
    j = skeleton.num_joints
    partner = np.asarray(skeleton.mirror_permutation)
    rest = np.asarray(skeleton.raw_offsets)
    if not np.allclose(rest[partner] * [-1.0, 1.0, 1.0], rest):
        raise ValueError(f"skeleton {skeleton.name!r}: the rest directions are not left-right symmetric")
    blocks = feature_slices(j)
    source = np.arange(feature_dim(j))
    sign = np.ones(feature_dim(j))
    sign[blocks["root_rot_vel"]] = -1.0  # a turn to the left becomes a turn to the right
    sign[blocks["root_lin_vel"].start] = -1.0  # sideways velocity in the facing frame

    def joints_block(block: slice, joints: np.ndarray, width: int, signs: np.ndarray) -> None:
        # row layout: one `width`-wide group per joint in `joints`; group k takes the partner's group, signed
        position = {int(joint): k for k, joint in enumerate(joints)}
        for k, joint in enumerate(joints):
            src = position[int(partner[joint])]
            dst = slice(block.start + k * width, block.start + (k + 1) * width)
            source[dst] = np.arange(block.start + src * width, block.start + (src + 1) * width)
            sign[dst] = signs

    x_flip = np.array([-1.0, 1.0, 1.0])
    joints_block(blocks["ric"], np.arange(1, j), 3, x_flip)
    joints_block(blocks["rot6d"], np.arange(1, j), 6, _SIX_D_SIGNS)
    joints_block(blocks["local_vel"], np.arange(j), 3, x_flip)
    left, right = skeleton.foot_joints  # contacts: (left feet..., right feet...)
    contacts = blocks["contacts"].start + np.arange(len(left) + len(right))
    source[contacts] = np.concatenate([contacts[len(left) :], contacts[: len(left)]])
    return source, sign


def mirror_hml_features(features: np.ndarray) -> np.ndarray:
    """HumanML3D (263) or KIT-ML (251) features (..., D), not normalised, of the left-right mirrored motion."""
    features = np.asarray(features)
    source, sign = _signed_permutation(int(features.shape[-1]))
    return (features[..., source] * sign).astype(features.dtype, copy=False)


def mirror_record(record: MotionRecord, action_mirror: list[int] | None = None) -> MotionRecord:
    """The mirror image of one clip: features, captions, action label; its id gets HumanML3D's 'M' prefix."""
    action = record.action
    if action != NO_ACTION and action_mirror is not None:
        action = action_mirror[action]
    meta = dict(record.meta or {})
    meta["mirror_of"] = record.id
    return replace(
        record,
        id=MIRROR_ID_PREFIX + record.id,
        motion=mirror_hml_features(record.motion),
        texts=[swap_left_right(t) for t in record.texts],
        action=action,
        meta=meta,
    )


def with_mirrors(records: list[MotionRecord], action_names: list[str] | None = None) -> list[MotionRecord]:
    """The clips followed by their mirror images (HumanML3D's train split with its M copies)."""
    action_mirror = mirrored_labels(list(action_names)) if action_names else None
    return list(records) + [mirror_record(r, action_mirror) for r in records]
