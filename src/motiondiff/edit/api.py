"""Editing a real motion with a trained model: in-between it or regenerate some of its body parts, B edits at once.

    from motiondiff.edit import load_input_motion, inbetween, edit_parts
    motion = load_input_motion("test:dataset-1_walk_active_001", module)
    result = inbetween(module, motion, "a person jumps", prefix=0.25, suffix=0.25, num_samples=3, seed=0)
    result = edit_parts(module, motion, "upper_body", "a person raises both hands", mode="repaint")

Inputs come from ``edit.inputs``; results hold de-normalised features, decoded joints of the representation's
skeleton and the masks of what was kept. ``condition=None`` edits without a condition (the model's ∅ condition,
guidance unused), also on text- or action-conditioned models. Sampling options (mode, guidance, sampler, steps, eta,
resample, hold_from, reconstruction) are those of ``edit.inpaint.SamplingOptions``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import torch

from motiondiff.data.representations import Representation
from motiondiff.edit.blend import DEFAULT_FRAMES, blend_boundaries
from motiondiff.edit.inpaint import SamplingOptions
from motiondiff.edit.inputs import InputMotion
from motiondiff.edit.masks import EditError, frame_keep, resolve_joints, to_frames
from motiondiff.edit.trajectory import close_root_path, needs_root_closure
from motiondiff.geometry.skeleton import Skeleton
from motiondiff.lit.conditions import check_action
from motiondiff.lit.generation import generate_features


@dataclass
class EditResult:
    """B edits (motions x samples, motion-major). Per edit: arrays of that motion's length N."""

    kind: str  # "inbetween" | "parts"
    features: list[np.ndarray]  # (N, D) de-normalised features of the edited motion
    joints: list[np.ndarray]  # (N, J, 3) decoded joints (the representation's skeleton), metres
    input_joints: list[np.ndarray]  # (N, J, 3) the input decoded the same way
    keep: list[np.ndarray]  # (N, D) bool: features taken from the input
    kept_frames: list[np.ndarray]  # (N,) bool: frames kept whole (in-betweening; all False for body parts)
    kept_joints: tuple[int, ...]  # joints whose features are kept (every joint for in-betweening)
    motion_index: list[int]  # which input motion each edit is of
    conditions: list  # the condition of each edit (None: unconditioned)
    settings: dict  # how the edit was made (mode, sampler, frames or parts, ...)
    skeleton: Skeleton = field(repr=False, default=None)  # skeleton of `joints`

    def __len__(self) -> int:
        return len(self.features)

    def kept_points(self, i: int) -> np.ndarray:
        """(N, J) bool: the joint positions of edit i the input fixes (kept frames x all joints, or all frames x
        kept joints)."""
        n, j = self.joints[i].shape[:2]
        points = np.zeros((n, j), dtype=bool)
        if self.kind == "parts":
            points[:, list(self.kept_joints)] = True
        else:
            points[self.kept_frames[i]] = True
        return points


# ---- editing ----------------------------------------------------------------------------------------------------
def _motions(motion) -> list[InputMotion]:
    motions = [motion] if isinstance(motion, InputMotion) else list(motion)
    if not motions:
        raise EditError("no motion to edit")
    return motions


def _conditions(module, condition, count: int) -> list:
    """One condition per motion, checked against what the model is conditioned on (None: unconditioned)."""
    conds = list(condition) if isinstance(condition, list | tuple) else [condition] * count
    if len(conds) != count:
        raise EditError(f"{len(conds)} conditions for {count} motions: give one per motion, or one for all")
    kind = module.condition_kind
    for c in conds:
        if c is None:
            continue
        if kind == "none":
            raise EditError("this model is unconditioned: drop the text/action (condition=None)")
        if kind == "text" and (not isinstance(c, str) or not c.strip()):
            raise EditError(f"this model is text-conditioned: give a non-empty text, got {c!r}")
        if kind == "action":
            check_action(c, list(module.hparams.get("action_names") or []), EditError)
    if any(c is None for c in conds) and not all(c is None for c in conds):
        raise EditError("give a condition for every motion or for none (a batch is conditioned or not)")
    return conds


def _prepare(module, motion, condition, num_samples: int, sampling: dict):
    """(motions, one condition per motion, checked sampling options) of an edit call."""
    motions = _motions(motion)
    conds = _conditions(module, condition, len(motions))
    if num_samples < 1:
        raise EditError(f"num_samples must be at least 1, got {num_samples}")
    options = SamplingOptions.from_kwargs(sampling, error=EditError)
    return motions, conds, options.resolved(module, conditioned=conds[0] is not None, error=EditError)


def _generator(module, generator: torch.Generator | None, seed: int | None) -> torch.Generator | None:
    if generator is not None or seed is None:
        return generator
    return torch.Generator(device=module.device).manual_seed(int(seed))


def _inpaint_motions(module, motions, keeps, conds, num_samples, options, generator, progress) -> list[np.ndarray]:
    """De-normalised features of num_samples edits per motion, motion-major, through the one generation chain with
    their known frames (SAMPLE_BATCH edits at a time, padded): the input's features exact where ``keeps[m]``."""
    order = [m for m in range(len(motions)) for _ in range(num_samples)]
    known = [motions[m].features for m in order]
    return generate_features(module, [conds[m] for m in order], torch.tensor([len(f) for f in known]),
                             generator=generator, known=known, keep=[keeps[m] for m in order],
                             what="the edited motion", progress=progress, **options.inpaint_kwargs())  # fmt: skip


def _result(module, kind, motions, conds, keeps, kept_frames, kept_joints, features, num_samples, settings):
    rep: Representation = module.representation
    order = [m for m in range(len(motions)) for _ in range(num_samples)]
    return EditResult(
        kind=kind,
        features=[f.astype(np.float32) for f in features],
        joints=[rep.decode_numpy(f).astype(np.float32) for f in features],
        input_joints=[motions[m].joints for m in order],
        keep=[keeps[m] for m in order],
        kept_frames=[kept_frames[m] for m in order],
        kept_joints=tuple(kept_joints),
        motion_index=order,
        conditions=[conds[m] for m in order],
        settings=settings,
        skeleton=rep.skeleton,
    )


def inbetween(
    module,
    motion: InputMotion | list[InputMotion],
    condition: Any = None,
    *,
    prefix: int | float | None = None,
    suffix: int | float | None = None,
    num_samples: int = 1,
    generator: torch.Generator | None = None,
    seed: int | None = None,
    close_root: bool = True,
    boundary_blend: int = DEFAULT_FRAMES,
    progress: bool = False,
    **sampling: Any,
) -> EditResult:
    """Keep the first ``prefix`` and last ``suffix`` frames of each motion and generate the frames between.

    ``prefix``/``suffix``: frames (int) or a fraction of the motion (float <= 1); None: 25% each. ``condition``: a
    text, an action name/id, None (unconditioned), or a list with one per motion. ``num_samples`` edits per motion.
    The generated frames next to kept ones fade from the kept motion into the model's over ``boundary_blend`` frames
    (motiondiff.edit.blend; 0: MDM's plain in-painting). With HumanML3D features the generated root velocities are
    then corrected (``close_root``, see motiondiff.edit.trajectory) so that the kept end decodes where the input had
    it."""
    motions, conds, options = _prepare(module, motion, condition, num_samples, sampling)
    settings = options.as_dict()
    rep: Representation = module.representation
    frames = [(to_frames(prefix, m.num_frames, "prefix"), to_frames(suffix, m.num_frames, "suffix")) for m in motions]
    kept_frames = [frame_keep(m.num_frames, p, s) for m, (p, s) in zip(motions, frames, strict=True)]
    keeps = [np.repeat(k[:, None], rep.dim, axis=1) for k in kept_frames]
    if isinstance(boundary_blend, bool) or not isinstance(boundary_blend, int | np.integer) or boundary_blend < 0:
        raise EditError(f"boundary_blend is a whole number of frames >= 0 (0: no blending), got {boundary_blend!r}")
    settings.update(kind="inbetween", prefix_frames=[p for p, _ in frames], suffix_frames=[s for _, s in frames],
                    close_root=bool(close_root and needs_root_closure(rep)), boundary_blend=int(boundary_blend),
                    seed=seed, num_samples=num_samples)  # fmt: skip
    gen = _generator(module, generator, seed)
    features = _inpaint_motions(module, motions, keeps, conds, num_samples, options, gen, progress)
    order = [m for m in range(len(motions)) for _ in range(num_samples)]
    features = [blend_boundaries(f, kept_frames[m], int(boundary_blend)) for f, m in zip(features, order, strict=True)]
    if settings["close_root"]:
        features = [
            close_root_path(f, motions[m].features, ~kept_frames[m]) for f, m in zip(features, order, strict=True)
        ]
    all_joints = range(rep.skeleton.num_joints)
    return _result(module, "inbetween", motions, conds, keeps, kept_frames, all_joints, features, num_samples, settings)


def edit_parts(
    module,
    motion: InputMotion | list[InputMotion],
    parts: str | int | list = "upper_body",
    condition: Any = None,
    *,
    num_samples: int = 1,
    generator: torch.Generator | None = None,
    seed: int | None = None,
    progress: bool = False,
    **sampling: Any,
) -> EditResult:
    """Regenerate the body ``parts`` of each motion from ``condition`` (a preset of the representation's skeleton
    such as 'upper_body', joint names/indices, or a list of them) and keep the rest of the body over every frame
    (MDM's body-part editing, named like its ``--edit_mode upper_body``: the legs and root trajectory are kept).
    ``parts`` means the same in sample.py's edit command, `MotionPipeline.edit_parts` and the demo."""
    motions, conds, options = _prepare(module, motion, condition, num_samples, sampling)
    settings = options.as_dict()
    rep: Representation = module.representation
    regenerated = set(resolve_joints(rep.skeleton, parts))
    joints = tuple(j for j in range(rep.skeleton.num_joints) if j not in regenerated)
    if not joints:
        raise EditError(f"the parts {parts!r} are the whole body ({rep.skeleton.name}), leaving nothing to keep: "
                        "generate a new motion instead (sample.py)")  # fmt: skip
    dims = rep.part_keep(joints)
    if dims.all():
        raise EditError(f"the parts {parts!r} leave the whole {rep.skeleton.name} motion kept, nothing to generate")
    keeps = [np.repeat(dims[None], m.num_frames, axis=0) for m in motions]
    kept_frames = [np.zeros(m.num_frames, dtype=bool) for m in motions]
    settings.update(kind="parts", parts=parts if isinstance(parts, str | int) else list(parts),
                    regenerated_joints=[rep.skeleton.joint_names[j] for j in sorted(regenerated)],
                    kept_joints=[rep.skeleton.joint_names[j] for j in joints], seed=seed, num_samples=num_samples)  # fmt: skip
    gen = _generator(module, generator, seed)
    features = _inpaint_motions(module, motions, keeps, conds, num_samples, options, gen, progress)
    return _result(module, "parts", motions, conds, keeps, kept_frames, joints, features, num_samples, settings)
