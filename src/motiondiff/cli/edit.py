"""`python edit.py ...`: in-between a motion or regenerate some of its body parts with a trained model, and write the
edited joints, features, the input, stick-figure videos and results.json with how well each edit kept the input.
`cleanup=feet` pins the generated feet during ground contacts; the frames and joints the edit kept do not move."""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig, ListConfig

from motiondiff.cli.common import UsageError, apply_step_rules, find_model, sampling_steps
from motiondiff.cli.outputs import cleanup_option, export_formats, video_size
from motiondiff.cli.validate import RULES_EDIT, check
from motiondiff.edit.cleanups import check_for_edit
from motiondiff.edit.inputs import clip_data_root, load_input_motion, read_bvh_input
from motiondiff.edit.masks import EditError, frames_from_seconds
from motiondiff.export.outputs import check_formats_for
from motiondiff.lit.conditions import check_action
from motiondiff.lit.generation import check_num_samples, feed_forward_shape
from motiondiff.model_files.loading import load_model as load_module
from motiondiff.pipelines import MotionPipeline
from motiondiff.pipelines.coverage import PromptCoverageWarning
from motiondiff.runtime.hardware import inference_precision, resolve_device
from motiondiff.runtime.prompt_text import check_text

KINDS = ("inbetween", "parts")


def edit_condition(cfg: DictConfig, module):
    """The text or action to edit towards; None edits unconditioned (allowed on every model)."""
    kind = module.condition_kind
    if cfg.text is not None and cfg.action is not None:
        raise UsageError("give text= or action=, not both")
    if kind == "none" and (cfg.text is not None or cfg.action is not None):
        raise UsageError("this model is unconditioned: drop text=/action=")
    if cfg.action is not None:
        if kind != "action":
            raise UsageError(f"this model is conditioned on {kind}: use text= (or nothing), not action=")
        return check_action(cfg.action, list(module.hparams.action_names))
    if cfg.text is not None:
        if kind != "text":
            raise UsageError(f"this model is conditioned on {kind}: use action= (or nothing), not text=")
        return check_text(cfg.text)
    return None


def _kept(cfg: DictConfig, name: str, fps: float):
    """prefix/suffix as the API takes them: frames (int) or a fraction (float <= 1); seconds with <name>_s."""
    seconds = cfg.get(f"{name}_s")
    if seconds is not None:
        return frames_from_seconds(float(seconds), fps)
    value = cfg.get(name)
    if isinstance(value, str) or isinstance(value, bool):
        raise UsageError(f"{name} must be a number (a fraction <= 1 like 0.25, or frames like 10), got {value!r}")
    return value


def _parts(cfg: DictConfig):
    parts = cfg.parts
    if isinstance(parts, ListConfig | list):
        return list(parts)
    if isinstance(parts, str) and "," in parts:
        return [p.strip() for p in parts.split(",") if p.strip()]
    return parts


def _check(cfg: DictConfig, module) -> int | None:
    if cfg.input is None:
        raise UsageError(
            "pass the motion to edit: input=<file.bvh>, input=<joints.npy> or a clip id such as "
            "input=test:dataset-1_walk_active_001"
        )
    if cfg.kind not in KINDS:
        raise UsageError(f"unknown kind {cfg.kind!r}; choose from {', '.join(KINDS)}")
    apply_step_rules(cfg, module)
    return sampling_steps(cfg, module)


def run(cfg: DictConfig) -> Path:
    check(cfg, RULES_EDIT)  # types and ranges before any work
    check_num_samples(cfg.num_samples)
    cfg.device = resolve_device(cfg.device)  # auto: the GPU where there is one
    formats, cleanup, size = export_formats(cfg), cleanup_option(cfg), video_size(cfg)
    check_for_edit(cleanup)
    ckpt = find_model(cfg.checkpoint, cfg.paths.output_dir)
    try:
        bvh = read_bvh_input(cfg.input) if cfg.input is not None else None  # a bad file is refused before the model
    except EditError as err:
        raise UsageError(str(err)) from None
    module = load_module(ckpt, cfg.device)
    check_formats_for(formats, module.representation.skeleton, cfg.get("bvh_names"))
    steps = _check(cfg, module)
    condition = edit_condition(cfg, module)
    fps = float(module.hparams.fps)
    try:
        data_root = Path(cfg.data) if cfg.data else clip_data_root(module, cfg.paths.data_dir, cfg.paths.cache_dir)
        length = None if cfg.length is None else frames_from_seconds(float(cfg.length), fps)
        motion = load_input_motion(cfg.input, module, data_root=data_root, start=frames_from_seconds(cfg.start, fps),
                                   frames=length, up_axis=str(cfg.get("up_axis", "auto")),
                                   smpl_model=cfg.get("smpl_model"), bvh=bvh)  # fmt: skip
        del bvh  # the window is encoded: the whole file's arrays are not needed any more
        if motion.up is not None:
            print(f"up axis of {cfg.input}: {motion.up.describe()}"
                  + ("" if motion.up.axis == "+y" else ", turned to y up"))  # fmt: skip
        if motion.window != (0, motion.total_frames):
            print(f"editing frames {motion.window[0]}..{motion.window[1]} of the input's {motion.total_frames} "
                  f"(the model's maximum is {module.hparams.max_frames}; choose the window with start=/length=)")  # fmt: skip
        sampling = {"mode": cfg.mode, "guidance": cfg.guidance, "sampler": cfg.sampler.name, "steps": steps,
                    "eta": float(cfg.sampler.eta), "resample": int(cfg.resample), "hold_from": cfg.hold_from,
                    "reconstruction": cfg.reconstruction, "progress": True}  # fmt: skip
        what = condition or "unconditioned"
        print(f"{cfg.kind} ({cfg.mode}) of {cfg.input} ({motion.num_frames} frames) x {cfg.num_samples}: {what!r}")
    except EditError as err:
        raise UsageError(str(err)) from None
    shape = feed_forward_shape(module, int(cfg.num_samples), int(module.hparams.max_frames))
    pipe = MotionPipeline(module, str(ckpt), inference_precision(cfg.get("precision", "auto"), cfg.device, shape))
    n, seed = int(cfg.num_samples), int(cfg.seed)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", PromptCoverageWarning)
        if cfg.kind == "inbetween":
            edited = pipe.inbetween(motion, condition, prefix=_kept(cfg, "prefix", fps), suffix=_kept(cfg, "suffix", fps),
                                    num_samples=n, seed=seed, close_root=bool(cfg.close_root),
                                    boundary_blend=cfg.boundary_blend, **sampling)  # fmt: skip
        else:
            edited = pipe.edit_parts(motion, condition, parts=_parts(cfg), num_samples=n, seed=seed, **sampling)
    for w in caught:
        print(f"warning: {w.message}", file=sys.stderr)
    edited = edited.cleaned(*cleanup) if cleanup else edited
    out = Path(HydraConfig.get().runtime.output_dir)
    result = edited.edit
    summary = {
        "checkpoint": str(ckpt),
        "input": {"source": str(cfg.input), "clip_id": motion.clip_id, "split": motion.split, "label": motion.label,
                  "captions": motion.captions, "window": list(motion.window), "total_frames": motion.total_frames,
                  "up_axis": None if motion.up is None else motion.up.to_json()},
        "condition": condition,
        "representation": module.representation.name,
        "settings": {**result.settings, "clip_x0": module.clip_rule, "timestep_spacing": module.timestep_spacing},
    }  # fmt: skip
    rows = edited.save(out, formats, cfg.get("bvh_names"), video_size=size, summary=summary)
    for r in rows:
        extra = (f"max boundary ratio {r['max_boundary_ratio']:.2f}" if result.kind == "inbetween"
                 else f"root-relative kept error {r['root_relative_kept_max_error_m']:.1e} m")  # fmt: skip
        print(f"  sample {r['index']}: kept-part error {r['kept_max_error_m']:.1e} m, {extra}")
    print(f"\n{len(rows)} edit(s) written to {out}")
    return out
