"""Which part of an input motion an edit keeps: frames (in-betweening) or feature dims (body-part editing).

Masks are boolean and True where the input is KEPT; the model generates the rest. Frame masks are over feature rows
(for HumanML3D features a row is a decoded frame). Dim masks come from the model's own representation
(``Representation.joint_dims``), so hml263 (SMPL-22 feature skeleton) and the rig representations (the rig's joints)
each get the dims that really describe the chosen joints; the root's dims hold the trajectory, so a part that keeps
the root (``lower_body``, as in MDM) keeps where the body goes.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from motiondiff.geometry.skeleton import Skeleton

DEFAULT_FRACTION = 0.25  # MDM's in-betweening keeps the first and last quarter by default


class EditError(ValueError):
    """An edit that cannot be done as asked (bad part, lengths, input); the message says how to fix it."""


# ---- frames -----------------------------------------------------------------------------------------------------
def frames_from_fraction(fraction: float, n: int) -> int:
    """round(fraction · n) frames of an n-frame motion, fraction in [0, 1]."""
    if not 0.0 <= fraction <= 1.0:
        raise EditError(f"a fraction of the motion must be between 0 and 1, got {fraction}")
    return int(round(fraction * n))


def frames_from_seconds(seconds: float, fps: float) -> int:
    """round(seconds · fps) frames."""
    if seconds < 0:
        raise EditError(f"a duration must be >= 0 seconds, got {seconds}")
    return int(round(seconds * fps))


def to_frames(value: int | float | None, n: int, name: str = "prefix") -> int:
    """A frame count from an int (frames) or a float <= 1 (fraction of the n-frame motion); None: the default 25%."""
    if value is None:
        return frames_from_fraction(DEFAULT_FRACTION, n)
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        raise EditError(f"{name} must be a number (frames as an int, a fraction as a float <= 1), got {value!r}")
    if isinstance(value, int | np.integer):
        if value < 0:
            raise EditError(f"{name} must be >= 0 frames, got {value}")
        return int(value)
    if value > 1.0:
        raise EditError(
            f"{name}={value} is a float above 1: give a fraction of the motion (<= 1, e.g. 0.25), a frame count "
            f"as an int (e.g. {int(value)}), or seconds with {name}_s"
        )
    return frames_from_fraction(float(value), n)


def frame_keep(n: int, prefix: int | None = None, suffix: int | None = None) -> np.ndarray:
    """(n,) bool: True on the first ``prefix`` and the last ``suffix`` frames (None: 25% of n each).

    At least one frame must be left to generate: prefix + suffix < n."""
    prefix = frames_from_fraction(DEFAULT_FRACTION, n) if prefix is None else int(prefix)
    suffix = frames_from_fraction(DEFAULT_FRACTION, n) if suffix is None else int(suffix)
    if prefix < 0 or suffix < 0:
        raise EditError(f"prefix and suffix must be >= 0 frames, got {prefix} and {suffix}")
    if prefix + suffix >= n:
        raise EditError(
            f"prefix ({prefix}) + suffix ({suffix}) frames cover the whole {n}-frame motion, leaving nothing to "
            "generate; keep fewer frames (e.g. prefix=0.25 suffix=0.25)"
        )
    keep = np.zeros(n, dtype=bool)
    keep[:prefix] = True
    keep[n - suffix :] = True
    return keep


# ---- body parts -------------------------------------------------------------------------------------------------
def resolve_joints(skeleton: Skeleton, spec: str | int | Sequence[str | int]) -> tuple[int, ...]:
    """Sorted joint indices of ``skeleton`` named by ``spec``: a preset of ``skeleton.parts`` ('lower_body',
    'left_arm', ...), a joint name or index, or a list mixing them (their union). A preset wins over a joint of
    the same name (SMPL-22's 'head' preset is neck + head)."""
    items = [spec] if isinstance(spec, str | int | np.integer) else list(spec)
    if not items:
        raise EditError(f"no body part given; presets of {skeleton.name}: {', '.join(sorted(skeleton.parts))}")
    joints: set[int] = set()
    for item in items:
        if isinstance(item, int | np.integer) and not isinstance(item, bool):
            if not 0 <= int(item) < skeleton.num_joints:
                raise EditError(
                    f"joint index {item} is out of range for skeleton {skeleton.name!r} "
                    f"({skeleton.num_joints} joints: 0..{skeleton.num_joints - 1})"
                )
            joints.add(int(item))
        elif isinstance(item, str) and item in skeleton.parts:
            joints.update(skeleton.parts[item])
        elif isinstance(item, str) and item in skeleton.joint_names:
            joints.add(skeleton.joint_names.index(item))
        else:
            raise EditError(
                f"unknown body part {item!r} for skeleton {skeleton.name!r}; presets: "
                f"{', '.join(sorted(skeleton.parts))} (or joint names: {', '.join(skeleton.joint_names)})"
            )
    return tuple(sorted(joints))
