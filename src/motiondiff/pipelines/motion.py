"""`MotionPipeline`: one object to generate and edit motion with a trained model (MDM or vvMDM).

    from motiondiff.pipelines import MotionPipeline
    pipe = MotionPipeline.from_pretrained("text")                 # the released text model
    out = pipe("a person walks forward", seconds=4, num_samples=2)
    out.save("walks", formats=["bvh", "mp4"])

The same object in-betweens and edits body parts of a motion (a BVH, a joints .npy, a dataset clip id or a motion it
made) and makes long motion from several prompts in order. Every call checks its input and raises UsageError with the
fix; sampling goes through the one generation chain (`motiondiff.lit.generation`).
"""

from __future__ import annotations

import os
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import torch

from motiondiff.data.representations.spec import bridge_from_spec
from motiondiff.edit.api import edit_parts as _edit_parts
from motiondiff.edit.api import inbetween as _inbetween
from motiondiff.edit.inputs import InputMotion, load_input_motion
from motiondiff.edit.long_motion import check_long_settings, generate_long, long_motion_info, seam_rows
from motiondiff.edit.masks import EditError
from motiondiff.lit.conditions import check_action, generation_frames, repeated
from motiondiff.lit.generation import (
    MAX_LONG_SAMPLES,
    check_num_samples,
    feed_forward_shape,
    generate_features,
    resolved_sampling,
    sampling_precision,
)
from motiondiff.lit.motion_diffusion import SAMPLER_STEPS
from motiondiff.model_files.loading import load_model
from motiondiff.model_files.resolve import find_model
from motiondiff.pipelines.coverage import load_coverage, warn_far
from motiondiff.pipelines.output import MotionOutput
from motiondiff.runtime.errors import UsageError
from motiondiff.runtime.hardware import inference_precision, resolve_device
from motiondiff.runtime.prompt_text import check_long_seconds, check_text, split_time
from motiondiff.runtime.settings import MAX_PROMPTS, MAX_SEGMENTS, check_count, check_settings


class MotionPipeline:
    """Generate (``__call__``), edit (``inbetween``, ``edit_parts``) and chain (``long``) motion with one model."""

    def __init__(self, model, source: str = "", precision: str = "auto"):
        self.model = model.eval()
        self.source = source
        # a text release's coverage bank: prompts far from every training caption warn (PromptCoverageWarning)
        self.coverage = load_coverage(self.model, source) if source else None
        shape = feed_forward_shape(self.model, 1, int(self.model.hparams.max_frames))  # one motion, as most calls
        self.precision = inference_precision(precision, str(self.model.device), shape)

    @classmethod
    def from_pretrained(cls, name_or_path: str | Path = "text", device: str = "cpu", precision: str = "auto"):
        """A released model by name ("text", "action", ...) or a .ckpt/.safetensors path. ``precision``: "auto"
        samples in bf16 where the hardware runs it natively (measured: docs/results/few_step_sampling.md), "32" in
        full precision, "bf16" forced."""
        path = find_model(name_or_path)
        return cls(load_model(path, resolve_device(device)), str(path), precision)

    # ---- what the model does ------------------------------------------------------------------------------------
    @property
    def fps(self) -> float:
        return float(self.model.hparams.fps)

    @property
    def max_seconds(self) -> float:
        return int(self.model.hparams.max_frames) / self.fps

    @property
    def condition_kind(self) -> str:
        """ "text", "action" or "none"."""
        return self.model.condition_kind

    @property
    def actions(self) -> list[str]:
        """The action names an action model knows (empty for other models)."""
        return list(self.model.hparams.get("action_names") or [])

    # ---- generation ---------------------------------------------------------------------------------------------
    def __call__(
        self,
        prompt: str | int | list | None = None,
        *,
        seconds: float | list[float] = 4.0,
        frames: int | list[int] | None = None,
        num_samples: int = 1,
        guidance: float | None = None,
        sampler: str = "auto",
        steps: int | None = None,
        eta: float = 0.0,
        seed: int = 0,
        smooth_sigma: float | None = None,
        progress: bool = False,
    ) -> MotionOutput:
        """``num_samples`` motions per prompt: texts (text models), action names or ids (action models) or None
        (unconditioned); one prompt or a list. ``seconds``: one length, or one per prompt (``frames``: the same in
        frames, in place of seconds). ``guidance``: the classifier-free guidance scale (None: the model's default);
        ``sampler``: auto (the model's own default: DPM-Solver++(2M) unless its recipe chose another on val), dpmpp,
        ddim or ddpm; ``steps``: sampler steps (None: 7 for DPM-Solver++, 50 for DDIM, the whole chain for DDPM, at
        most the model's T); ``smooth_sigma``: vvMDM's Gaussian filter over time, frames."""
        seed, smooth_sigma = self._seed_and_sigma(seed, smooth_sigma)
        prompts = self._prompts(prompt)
        if frames is None:
            lengths = [self._frames(s) for s in self._per_prompt(seconds, len(prompts), "seconds")]
        else:
            lengths = [generation_frames(self.model, None, frames=f) for f in self._per_prompt(frames, len(prompts), "frames")]  # fmt: skip
        far = warn_far(self.model, self.coverage, prompts)
        n = self._count(num_samples)
        sampling = self._sampling(guidance, sampler, steps, eta)
        conditions = [p for p in prompts for _ in range(n)]
        lengths = torch.tensor([f for f in lengths for _ in range(n)])
        generator = torch.Generator(device=self.model.device).manual_seed(seed)
        feats = generate_features(self.model, conditions, lengths, batch_size=64, generator=generator,
                                  precision=self.precision, progress=progress, **sampling)  # fmt: skip
        joints = [self.model.representation.decode_numpy(f).astype(np.float32) for f in feats]
        info = {"model": self.source, **sampling, "seed": int(seed), "smooth_sigma": None,
                "precision": self.precision, "joints_changed": False, "coverage_warnings": far}  # fmt: skip
        return self._output(joints, feats, [self._label(c) for c in conditions], info).smoothed(smooth_sigma)

    def long(
        self,
        prompts: list,
        seconds: float | list[float] = 4.0,
        *,
        overlap: float = 1.0,
        blend: float = 0.25,
        num_samples: int = 1,
        seed: int = 0,
        guidance: float | None = None,
        sampler: str = "auto",
        steps: int | None = None,
        eta: float = 0.0,
        mode: str = "overwrite",
        resample: int = 1,
        smooth_sigma: float | None = None,
        progress: bool = False,
    ) -> MotionOutput:
        """One motion per sample that does the prompts in order, each for its seconds (plain strings, or
        "text:seconds"; action names for an action model); each part continues from the last ``overlap`` seconds of
        the one before, of which the last ``blend`` seconds are cross-faded. ``mode``: how the held frames are kept
        (``edit.inpaint.EDIT_MODES``); ``resample``: RePaint's repeats per step (1: none). Sampling options as for
        a call. results.json gets the windows and, per motion, the speed jump at each seam against its median."""
        seed, smooth_sigma = self._seed_and_sigma(seed, smooth_sigma)
        if not isinstance(prompts, list | tuple) or not prompts:
            raise UsageError("long() takes a list of prompts, e.g. ['a person walks:4', 'a person waves:2']")
        check_count("timed prompts", len(prompts), MAX_SEGMENTS, "make several long motions")
        items, secs = [], []
        for item, s in zip(prompts, self._per_prompt(seconds, len(prompts), "seconds"), strict=True):
            text, timed = split_time(item)
            items.append(text)
            secs.append(timed if timed is not None else check_settings(seconds=s)["seconds"])
        check_long_seconds(secs)
        conditions = self._prompts(items)
        labels = [self._label(c) for c in conditions]
        overlap, blend = check_long_settings(self.model, labels, secs, overlap, blend, mode, resample)
        far = warn_far(self.model, self.coverage, conditions)
        n = check_num_samples(num_samples, MAX_LONG_SAMPLES)  # a long motion's windows chain: one batch
        sampling = self._sampling(guidance, sampler, steps, eta)
        generator = torch.Generator(device=self.model.device).manual_seed(seed)
        segments = [(repeated(self.model, c, n), s) for c, s in zip(conditions, secs, strict=True)]
        try:
            with sampling_precision(self.model, self.precision):
                result = generate_long(self.model, segments, overlap_s=overlap, blend_s=blend, num_samples=n,
                                       generator=generator, labels=labels, mode=mode, resample=int(resample),
                                       progress=progress, **sampling)  # fmt: skip
        except ValueError as err:
            raise UsageError(str(err)) from None
        info = {"model": self.source, "segments": result.segments, "seed": seed, **sampling,
                "coverage_warnings": far, "long_motion": long_motion_info(result, mode, self.model),
                "per_motion": seam_rows(result, smooth_sigma)}  # fmt: skip
        title = ", ".join(f"{label}:{s:g}" for label, s in zip(labels, secs, strict=True))
        joints = [j.astype(np.float32) for j in result.joints]
        return self._output(joints, list(result.features), [title] * n, info).smoothed(smooth_sigma)

    # ---- editing ------------------------------------------------------------------------------------------------
    def inbetween(self, motion, prompt=None, *, prefix=None, suffix=None, num_samples: int = 1, seed: int = 0,
                  up_axis: str = "auto", smpl_model=None, **sampling: Any) -> MotionOutput:  # fmt: skip
        """Keep the first ``prefix`` and last ``suffix`` of ``motion`` (frames, or a fraction; default 25% each) and
        generate the frames between, following ``prompt``. ``motion``: a .bvh/.npy/.npz path, a dataset clip id, or
        a MotionOutput (its first motion). ``up_axis``: a file's up axis, "auto" (detected) or forced ("z", "-z",
        ...; see `motiondiff.edit.load_input_motion`); ``smpl_model``: the SMPL body model .npz an SMPL parameter
        file (AMASS) needs for its skeleton."""
        source = self._input(motion, up_axis, smpl_model)
        return self._edited(_inbetween, source, prompt, dict(prefix=prefix, suffix=suffix), num_samples, seed, sampling)

    def edit_parts(self, motion, prompt=None, *, parts="upper_body", num_samples: int = 1, seed: int = 0,
                   up_axis: str = "auto", smpl_model=None, **sampling: Any) -> MotionOutput:  # fmt: skip
        """Regenerate ``parts`` of ``motion`` (a preset such as "upper_body" or joint names) from ``prompt`` and keep
        the rest of the body as it is, over every frame (MDM's body-part editing). ``up_axis``, ``smpl_model`` as in
        `inbetween`."""
        source = self._input(motion, up_axis, smpl_model)
        return self._edited(_edit_parts, source, prompt, {"parts": parts}, num_samples, seed, sampling)

    # ---- helpers ------------------------------------------------------------------------------------------------
    def _edited(self, fn, source: InputMotion, prompt, options: dict, num_samples, seed, sampling) -> MotionOutput:
        seed, _ = self._seed_and_sigma(seed, None)
        condition = None if prompt is None else self._prompts(prompt)[0]
        warn_far(self.model, self.coverage, [condition])
        try:
            with sampling_precision(self.model, self.precision):
                result = fn(self.model, source, condition=condition, num_samples=self._count(num_samples),
                            seed=seed, **options, **self._edit_sampling(sampling))  # fmt: skip
        except (EditError, ValueError) as err:
            raise UsageError(str(err)) from None
        info = {"model": self.source, "input": source.source, **result.settings}
        out = self._output(
            list(result.joints), list(result.features), [self._label(c) for c in result.conditions], info
        )
        return replace(out, edit=result, source=source)

    def _input(self, motion, up_axis: str = "auto", smpl_model=None) -> InputMotion:
        if isinstance(motion, InputMotion):  # already loaded (edit.load_input_motion: a window, a data root, ...)
            return motion
        if isinstance(motion, MotionOutput):  # its own features, as made (canonical placement, any representation)
            if motion.representation.name != self.model.representation.name:
                raise UsageError(f"this motion is in {motion.representation.name} features; the model edits "
                                 f"{self.model.representation.name}: save it as joints (.npy) or BVH and edit that file")  # fmt: skip
            n = min(len(motion.features[0]), int(self.model.hparams.max_frames))
            feats = np.asarray(motion.features[0][:n], dtype=np.float32)
            joints = self.model.representation.decode_numpy(feats)
            return InputMotion(feats, joints, "generated", self.fps, (0, n), len(motion.features[0]),
                               captions=[motion.prompts[0]] if motion.prompts[0] else [])  # fmt: skip
        if not isinstance(motion, str | os.PathLike):  # an array is not an id: printing it as one helps nobody
            hint = (
                ": save joints (frames, J, 3) with np.save and pass the .npy path" if hasattr(motion, "shape") else ""
            )
            raise UsageError(f"motion must be a .bvh/.npy/.npz path, a dataset clip id or a MotionOutput, got a "
                             f"{type(motion).__name__}{hint}")  # fmt: skip
        return self._load(motion, up_axis, smpl_model)

    def _load(self, source, up_axis: str = "auto", smpl_model=None) -> InputMotion:
        try:
            return load_input_motion(source, self.model, up_axis=up_axis, smpl_model=smpl_model)
        except (EditError, ValueError) as err:
            raise UsageError(str(err)) from None

    def _output(self, joints, feats, prompts, info) -> MotionOutput:
        rep = self.model.representation
        bridge = bridge_from_spec(self.model.hparams.get("representation"), self.model.hparams.feature_dim)
        return MotionOutput(joints, [np.asarray(f) for f in feats], prompts, self.fps, rep.skeleton, rep, info, bridge)

    def _prompts(self, prompt) -> list:
        items = list(prompt) if isinstance(prompt, list | tuple) else [prompt]
        if not items:
            raise UsageError("give at least one prompt")
        check_count("prompts", len(items), MAX_PROMPTS, "call again with the rest")
        kind = self.condition_kind
        if kind == "none":
            if any(p is not None for p in items):
                raise UsageError("this model is unconditioned: call it without a prompt")
            return items
        if kind == "action":
            return [self._check_action(p) for p in items]
        return [check_text(p) for p in items]

    def _check_action(self, action):
        return check_action(action, self.actions)

    def _label(self, condition) -> str | None:
        if isinstance(condition, int | np.integer) and self.actions:
            return self.actions[int(condition)]
        return condition

    def _frames(self, seconds) -> int:
        return generation_frames(self.model, seconds, name="seconds")

    @staticmethod
    def _per_prompt(value, n: int, name: str) -> list:
        values = list(value) if isinstance(value, list | tuple) else [value] * n
        if len(values) != n:
            raise UsageError(f"{name}: give one value or one per prompt ({n}), got {len(values)}")
        return values

    @staticmethod
    def _count(num_samples) -> int:
        return check_num_samples(num_samples)  # 1..MAX_NUM_SAMPLES

    def _sampling(self, guidance, sampler, steps, eta) -> dict:
        checked = check_settings(guidance=guidance, steps=steps, eta=eta)  # the commands' rules (runtime.settings)
        guidance = self.model.default_guidance if checked["guidance"] is None else checked["guidance"]
        if sampler not in ("auto", *SAMPLER_STEPS):
            raise UsageError(f"sampler must be auto or one of {', '.join(SAMPLER_STEPS)}, got {sampler!r}")
        sampler, steps = resolved_sampling(self.model, sampler, checked["steps"])
        return {"guidance": float(guidance), "sampler": sampler, "steps": steps, "eta": checked["eta"]}

    @staticmethod
    def _seed_and_sigma(seed, smooth_sigma) -> tuple[int, float | None]:
        checked = check_settings(seed=seed, smooth_sigma=smooth_sigma)
        return checked["seed"], checked["smooth_sigma"]

    @staticmethod
    def _edit_sampling(sampling: dict) -> dict:
        """An edit's sampling keywords checked by the same rules as a call's (guidance, steps, eta, resample)."""
        ruled = {k: sampling[k] for k in ("guidance", "steps", "eta", "resample") if k in sampling}
        return {**sampling, **check_settings(**ruled)}
