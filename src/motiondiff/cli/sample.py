"""`python sample.py ...`: generate motion from text, an action name or nothing, and write joints, features and
stick-figure videos (or, with render=mesh and smpl_model=, videos of an SMPL body), plus results.json with what each
sample measurably does.

Timed prompts, `prompts="[a person walks forward:4, a person waves:3]"` (or `action="[walk:4, wave:3]"`), make ONE
long motion that follows them in order (`edit.long_motion`); `smooth_sigma=` applies vvMDM's temporal filter and
`cleanup=bones` puts the joints on one fixed skeleton (`edit.rigid_bones`) and `cleanup=feet` pins the feet during
ground contacts (`edit.foot_cleanup`)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import torch
from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig, ListConfig

from motiondiff.cli.common import (
    UsageError,
    apply_clip_x0,
    find_model,
    sampling_steps,
    to_dict,
)
from motiondiff.cli.outputs import (
    cleanup_option,
    export_formats,
    render_option,
    save_samples,
    smoothing_sigma,
)
from motiondiff.cli.prompt_inputs import check_one_source, read_prompts_file, split_timed
from motiondiff.cli.validate import RULES_SAMPLE, check
from motiondiff.edit.inpaint import EDIT_MODES
from motiondiff.edit.long_motion import boundary_report, generate_long
from motiondiff.edit.smoothing import smooth_joints
from motiondiff.export.naming import slug, unique_stems
from motiondiff.export.outputs import check_formats_for
from motiondiff.lit.conditions import check_action, generation_frames, repeated
from motiondiff.lit.generation import (
    MAX_LONG_SAMPLES,
    check_num_samples,
    feed_forward_shape,
    generate_features,
    sampling_precision,
)
from motiondiff.lit.motion_diffusion import MotionDiffusion
from motiondiff.model_files.loading import load_model
from motiondiff.pipelines.coverage import far_prompts, load_coverage
from motiondiff.runtime.atomic import finite_or_null, write_json
from motiondiff.runtime.hardware import inference_precision, resolve_device
from motiondiff.runtime.prompt_text import check_text


def collect_prompts(cfg: DictConfig, module: MotionDiffusion) -> list[str | None]:
    """The prompts to generate for: texts, action names, or [None] for unconditioned generation."""
    kind = module.condition_kind
    check_one_source(cfg)
    given = [x for x in (cfg.text, cfg.prompts, cfg.prompts_file, cfg.action) if x is not None]
    if kind == "none":
        if given:
            raise UsageError("this model is unconditioned: drop text=/prompts=/action=")
        return [None]
    if kind == "action":
        if cfg.action is None:
            raise UsageError(
                f"this model is conditioned on actions: pass action=<one of {module.hparams.action_names}>"
            )
        names = [cfg.action] if isinstance(cfg.action, str) else list(cfg.action)
        return [check_action(name, list(module.hparams.action_names)) for name in names]
    if cfg.prompts_file is not None:
        texts = read_prompts_file(cfg.prompts_file)
    elif cfg.prompts is not None:
        texts = list(cfg.prompts) if isinstance(cfg.prompts, ListConfig | list) else [cfg.prompts]
    elif cfg.text is not None:
        texts = [cfg.text]
    else:
        raise UsageError(
            "this model is text-conditioned: pass text='a person walks forward' (or prompts=/prompts_file=)"
        )
    return [check_text(t) for t in texts]


def num_frames(cfg: DictConfig, module: MotionDiffusion) -> int:
    """frames= as given, else length= in seconds."""
    return generation_frames(module, cfg.length, frames=cfg.frames)


def run(cfg: DictConfig) -> Path:
    check(cfg, RULES_SAMPLE)  # types and ranges before any work
    check_num_samples(cfg.num_samples)
    cfg.device = resolve_device(cfg.device)  # auto: the GPU where there is one
    if cfg.get("method", "mdm") not in ("mdm", "vvmdm"):  # sample.py runs method=guidedmotion with cli.sample_guided
        raise UsageError(f"unknown method={cfg.method!r}; choose mdm, vvmdm or guidedmotion")
    out = Path(HydraConfig.get().runtime.output_dir)
    ckpt = find_model(cfg.checkpoint, cfg.paths.output_dir, "action" if cfg.action is not None else "text")
    plain, seconds = split_timed(cfg)  # prompt syntax errors before the model loads
    if seconds is not None:  # a long motion's windows chain, sampled in one batch
        check_num_samples(cfg.num_samples, MAX_LONG_SAMPLES)
    formats, cleanup, body = export_formats(cfg), cleanup_option(cfg), render_option(cfg)
    module = load_model(ckpt, cfg.device)
    check_formats_for(formats, module.representation.skeleton, cfg.get("bvh_names"), body)
    prompts = collect_prompts(plain, module)
    far = [r.warning() for r in far_prompts(module, load_coverage(module, ckpt), prompts)]
    for line in far:  # one line per far prompt, before the sampling
        print(f"warning: {line}", file=sys.stderr)
    frames = num_frames(cfg, module) if seconds is None else None
    sigma = smoothing_sigma(cfg, module)
    if cfg.num_samples < 1:
        raise UsageError(f"num_samples must be at least 1, got {cfg.num_samples}")
    guidance = module.default_guidance if cfg.guidance is None else float(cfg.guidance)
    if guidance < 0:
        raise UsageError(f"guidance must be >= 0, got {guidance}")
    steps = sampling_steps(cfg, module)
    apply_clip_x0(cfg, module)
    generator = torch.Generator(device=cfg.device).manual_seed(int(cfg.seed))
    shape = feed_forward_shape(module, int(cfg.num_samples), frames or int(module.hparams.max_frames))
    precision = inference_precision(cfg.get("precision", "auto"), cfg.device, shape)
    summary = {"checkpoint": str(ckpt), "sampler": to_dict(cfg.sampler), "guidance": guidance, "steps": steps,
               "precision": precision, "clip_x0": module.clip_rule, "coverage_warnings": far}  # fmt: skip
    if seconds is not None:
        with sampling_precision(module, precision):
            summary.update(sample_long(cfg, out, module, prompts, seconds, guidance, steps, generator, sigma, formats,
                                       cleanup, body))  # fmt: skip
        write_json(out / "results.json", finite_or_null(summary))  # an undefined measure: null
        print(f"\n{cfg.num_samples} long motion(s) of {summary['long_motion']['seconds']:g} s written to {out}")
        return out
    results = []
    for prompt, stem in zip(prompts, unique_stems(prompts), strict=True):
        print(f"sampling {cfg.num_samples} x {frames} frames for {prompt or 'unconditioned'!r}")
        n = int(cfg.num_samples)
        feats = generate_features(module, [prompt] * n, torch.full((n,), frames), generator=generator,
                                  guidance=guidance, sampler=cfg.sampler.name, steps=steps, eta=float(cfg.sampler.eta),
                                  progress=True, precision=precision)  # fmt: skip
        feats = np.stack(feats)
        results += save_samples(out, prompt, feats, module, formats, sigma, stem=stem, cleanup=cleanup,
                                rig_names=cfg.get("bvh_names"), body=body)  # fmt: skip
    summary["samples"] = results
    write_json(out / "results.json", finite_or_null(summary))  # an undefined measure: null
    print(f"\n{len(results)} sample(s) written to {out}")
    return out


def long_motion_settings(cfg, module, prompts: list, seconds: list[float]) -> tuple[float, float]:
    """(overlap, blend) seconds for timed prompts, or a clear error for settings this model cannot do."""
    if cfg.frames is not None:
        raise UsageError("timed prompts set their own lengths: drop frames= (length= is ignored too)")
    if cfg.edit_mode not in EDIT_MODES:
        raise UsageError(f"edit_mode must be one of {', '.join(EDIT_MODES)}, got {cfg.edit_mode!r}")
    if isinstance(cfg.resample, bool) or not isinstance(cfg.resample, int) or cfg.resample < 1:
        raise UsageError(f"resample is RePaint's repeats per step, a whole number >= 1 (1: none), got {cfg.resample!r}")
    fps, max_frames = module.hparams.fps, module.hparams.max_frames
    overlap, blend = cfg.overlap, cfg.blend
    if isinstance(overlap, bool) or not isinstance(overlap, int | float) or not 0 < overlap * fps < max_frames - 0.5:
        raise UsageError(
            f"overlap is the seconds each prompt continues from the one before: more than 0 and less than this "
            f"model's {max_frames / fps:g} s, got {overlap!r}"
        )
    if isinstance(blend, bool) or not isinstance(blend, int | float) or not 0 <= blend < overlap:
        raise UsageError(f"blend is the seconds at the end of the overlap that are cross-faded: 0 to less than "
                         f"overlap={overlap:g}, got {blend!r}")  # fmt: skip
    short = [f"{p}:{s:g}" for p, s in zip(prompts, seconds, strict=True) if round(s * fps) < 1]
    if short:
        raise UsageError(f"each timed prompt needs at least one frame (1/{fps:g} s): {', '.join(short)}")
    return float(overlap), float(blend)


def sample_long(cfg, out, module, prompts, seconds, guidance, steps, generator, sigma, formats, cleanup=(), body=None):
    """One long motion per sample through the timed prompts; returns the results.json entries."""
    overlap, blend = long_motion_settings(cfg, module, prompts, seconds)
    n = cfg.num_samples
    segments = [(repeated(module, p, n), s) for p, s in zip(prompts, seconds, strict=True)]
    print(f"sampling {n} long motion(s) through {len(prompts)} timed prompts ({sum(seconds):g} s)")
    long = generate_long(
        module, segments, overlap_s=overlap, blend_s=blend, num_samples=n, guidance=guidance,
        sampler=cfg.sampler.name, steps=steps, eta=float(cfg.sampler.eta), generator=generator, mode=cfg.edit_mode,
        resample=int(cfg.resample), labels=prompts, progress=True,
    )  # fmt: skip
    title = ", ".join(f"{p}:{s:g}" for p, s in zip(prompts, seconds, strict=True))
    shown = [(s["start"], str(s["label"])) for s in long.segments]  # the videos show the prompt playing
    rows = save_samples(out, title, long.features, module, formats, sigma, stem=f"long_{slug(' then '.join(prompts))}",
                        cleanup=cleanup, title=shown, rig_names=cfg.get("bvh_names"), body=body)  # fmt: skip
    seams, blends = [w.plan.start for w in long.windows[1:]], [w.plan.blend for w in long.windows[1:]]
    for row, joints, boundaries in zip(rows, long.joints, long.boundaries, strict=True):
        if sigma is not None:  # the filter also runs across the seams: how they look in the saved joints
            after = boundary_report(smooth_joints(joints, sigma), seams, long.fps, blends=blends)
            for b, a in zip(boundaries, after, strict=True):
                b["ratio_smoothed"] = a["ratio"]
        row["frames"] = long.num_frames
        row["boundaries"] = boundaries
        row["max_boundary_ratio"] = max((b["ratio"] for b in boundaries), default=None)
    windows = [{"segment": w.plan.segment, "start": w.plan.start, "end": w.plan.end, "overlap": w.plan.overlap,
                "blend": w.plan.blend} for w in long.windows]  # fmt: skip
    info = {"segments": long.segments, "windows": windows, "frames": long.num_frames,
            "seconds": long.num_frames / long.fps, "overlap_frames": max((w["overlap"] for w in windows), default=0),
            "blend_frames": max((w["blend"] for w in windows), default=0), "edit_mode": cfg.edit_mode,
            "max_frames": int(module.hparams.max_frames)}  # fmt: skip
    return {"long_motion": info, "samples": rows}
