"""`python sample.py ...`: generate motion from text, an action name or nothing, and write joints, features and
stick-figure videos (or, with render=mesh and smpl_model=, videos of an SMPL body), plus results.json with what each
sample measurably does.

Timed prompts, `prompts="[a person walks forward:4, a person waves:3]"` (or `action="[walk:4, wave:3]"`), make ONE
long motion that follows them in order (`edit.long_motion`); `smooth_sigma=` applies vvMDM's temporal filter and
`cleanup=bones` puts the joints on one fixed skeleton (`edit.rigid_bones`) and `cleanup=feet` pins the feet during
ground contacts (`edit.foot_cleanup`)."""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig, ListConfig

from motiondiff.cli.common import UsageError, apply_step_rules, find_model, sampling_steps, to_dict
from motiondiff.cli.outputs import cleanup_option, export_formats, render_option, smoothing_sigma, video_size
from motiondiff.cli.prompt_inputs import check_one_source, check_prompt_inputs, read_prompts_file, split_timed
from motiondiff.cli.validate import RULES_SAMPLE, check
from motiondiff.export.outputs import check_formats_for
from motiondiff.lit.conditions import check_action, generation_frames
from motiondiff.lit.generation import MAX_LONG_SAMPLES, check_num_samples, feed_forward_shape
from motiondiff.lit.motion_diffusion import MotionDiffusion
from motiondiff.model_files.loading import load_model
from motiondiff.pipelines import MotionPipeline
from motiondiff.pipelines.coverage import PromptCoverageWarning, far_prompts
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


def run(cfg: DictConfig) -> Path:
    """Checked config -> MotionPipeline -> call (or `long` for timed prompts) -> MotionOutput.save."""
    check(cfg, RULES_SAMPLE)  # types and ranges before any work
    check_num_samples(cfg.num_samples)
    cfg.device = resolve_device(cfg.device)  # auto: the GPU where there is one
    if cfg.get("method", "mdm") not in ("mdm", "vvmdm"):  # sample.py runs method=guidedmotion with cli.sample_guided
        raise UsageError(f"unknown method={cfg.method!r}; choose mdm, vvmdm or guidedmotion")
    out = Path(HydraConfig.get().runtime.output_dir)
    ckpt = find_model(cfg.checkpoint, cfg.paths.output_dir, "action" if cfg.action is not None else "text")
    check_prompt_inputs(cfg)  # prompt text, counts and syntax before the model loads (the entry did it too)
    plain, seconds = split_timed(cfg)
    if seconds is not None:  # a long motion's windows chain, sampled in one batch
        check_num_samples(cfg.num_samples, MAX_LONG_SAMPLES)
        if cfg.frames is not None:
            raise UsageError("timed prompts set their own lengths: drop frames= (length= is ignored too)")
    formats, cleanup, body, size = export_formats(cfg), cleanup_option(cfg), render_option(cfg), video_size(cfg)
    module = load_model(ckpt, cfg.device)
    check_formats_for(formats, module.representation.skeleton, cfg.get("bvh_names"), body)
    prompts = collect_prompts(plain, module)
    frames = generation_frames(module, cfg.length, frames=cfg.frames) if seconds is None else None
    sigma = smoothing_sigma(cfg, module)
    guidance = module.default_guidance if cfg.guidance is None else float(cfg.guidance)  # checked >= 0 by the rules
    apply_step_rules(cfg, module)  # before the steps: fitting them checks them against the spacing asked for
    steps = sampling_steps(cfg, module)
    shape = feed_forward_shape(module, int(cfg.num_samples), frames or int(module.hparams.max_frames))
    pipe = MotionPipeline(module, str(ckpt), inference_precision(cfg.get("precision", "auto"), cfg.device, shape))
    far = [r.warning() for r in far_prompts(module, pipe.coverage, prompts)]
    for line in far:  # one line per far prompt, before the sampling
        print(f"warning: {line}", file=sys.stderr)
    options = dict(num_samples=int(cfg.num_samples), guidance=guidance, sampler=cfg.sampler.name, steps=steps,
                   eta=float(cfg.sampler.eta), seed=int(cfg.seed), smooth_sigma=sigma, progress=True)  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PromptCoverageWarning)  # printed above, as one line each
        if seconds is None:
            print(f"sampling {cfg.num_samples} x {frames} frames for {len(prompts)} prompt(s)")
            motions = pipe(prompts, frames=frames, **options)
        else:
            print(
                f"sampling {cfg.num_samples} long motion(s) through {len(prompts)} timed prompts ({sum(seconds):g} s)"
            )
            motions = pipe.long(prompts, seconds, overlap=cfg.overlap, blend=cfg.blend, mode=cfg.edit_mode,
                                resample=cfg.resample, **options)  # fmt: skip
    motions = motions.cleaned(*cleanup) if cleanup else motions
    summary = {"checkpoint": str(ckpt), "sampler": to_dict(cfg.sampler), "guidance": guidance, "steps": steps,
               "precision": pipe.precision, "clip_x0": module.clip_rule, "timestep_spacing": module.timestep_spacing,
               "coverage_warnings": far,
               **({"long_motion": motions.info["long_motion"]} if seconds is not None else {})}  # fmt: skip
    rows = motions.save(out, formats, cfg.get("bvh_names"), body=body, video_size=size, summary=summary)
    what = f"long motion(s) of {motions.seconds():g} s" if seconds is not None else "sample(s)"
    print(f"\n{len(rows)} {what} written to {out}")
    return out
