"""The `cleanup=` option of sample.py, edit.py and `MotionOutput.cleaned`: which clean-ups run on generated joints,
in which order, and what each reported. `bones` (one fixed skeleton, `edit.rigid_bones`) runs before `feet` (feet
pinned during ground contacts, `edit.foot_cleanup`): the foot clean-up keeps every bone's length, so the result
stays rigid."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from motiondiff.edit.foot_cleanup import clean_foot_skate
from motiondiff.edit.rigid_bones import rigid_bones
from motiondiff.geometry.skeleton import Skeleton
from motiondiff.runtime.errors import UsageError

CLEANUPS = ("bones", "feet")  # the order they run in
HELP = ("cleanup=bones (one fixed skeleton: the files of every format then agree with the joints), cleanup=feet "
        "(pin the feet during ground contacts), cleanup=[bones,feet] for both, or cleanup=none")  # fmt: skip


def parse_cleanup(value) -> tuple[str, ...]:
    """`value` (None, "none", "feet", "bones,feet" or a list of names) as the clean-ups to run, in running order."""
    if value is None:
        return ()
    names = value.split(",") if isinstance(value, str) else list(value) if isinstance(value, Sequence) else None
    if names is None or not all(isinstance(n, str) for n in names):
        raise UsageError(f"cleanup={value!r}: choose {HELP}")
    names = [n.strip().lower() for n in names if n.strip()]
    if names in ([], ["none"]):
        return ()
    unknown = [n for n in names if n not in CLEANUPS]
    if unknown:
        raise UsageError(f"cleanup={value!r}: unknown clean-up {unknown[0]!r}; choose {HELP}")
    return tuple(c for c in CLEANUPS if c in names)


def check_for_edit(cleanups: tuple[str, ...]) -> None:
    """An edit keeps part of its input exactly; the bone clean-up refits every frame, so it is refused there."""
    if "bones" in cleanups:
        raise UsageError("cleanup=bones refits every frame and would move the part the edit kept: use cleanup=feet "
                         "in edit.py, or cleanup=bones on a sample.py motion")  # fmt: skip


def apply_cleanups(
    joints: np.ndarray, skeleton: Skeleton, fps: float, cleanups: tuple[str, ...], keep: np.ndarray | None = None
) -> tuple[np.ndarray, dict]:
    """Joints (N, J, 3) after the `cleanups` (in `CLEANUPS` order), with one report per clean-up: {"bones": ...,
    "foot_cleanup": ...}. `keep`: frames (N,) or points (N, J) that must not move (an edit's kept part); the bone
    clean-up refits every frame, so it refuses a `keep`."""
    reports = {}
    out = np.asarray(joints, dtype=np.float64)
    if keep is not None and np.asarray(keep).any():
        check_for_edit(cleanups)
    if "bones" in cleanups:
        fitted = rigid_bones(out, skeleton, fps)
        out, reports["bones"] = fitted.joints, fitted.summary()
    if "feet" in cleanups:
        cleaned = clean_foot_skate(out, skeleton, fps, keep=keep)
        out, reports["foot_cleanup"] = cleaned.joints, cleaned.summary()
    return out.astype(np.asarray(joints).dtype), reports
