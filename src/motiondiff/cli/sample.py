"""`python sample.py ...`: generate motion from text, an action name or nothing, and write joints, features and
stick-figure videos, plus results.json with what each sample measurably does."""

from __future__ import annotations

import json
import re
from dataclasses import asdict
from pathlib import Path

import numpy as np
import torch
from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig, ListConfig

from motiondiff.cli.common import UsageError, find_checkpoint, text_encoder_kwargs, to_dict
from motiondiff.data.captions import measure
from motiondiff.data.representation_spec import bridge_from_spec
from motiondiff.eval.behaviour import mean_joint_speed
from motiondiff.lit.diffusion import MotionDiffusionModule

MAX_TEXT_CHARS = 1000  # far beyond any caption the encoders were trained on (CLIP keeps 77 tokens)


def load_module(path: Path, device: str = "cpu") -> MotionDiffusionModule:
    module = MotionDiffusionModule.load_from_checkpoint(path, map_location=device, weights_only=True)
    return module.eval()


def check_text(text) -> str:
    if not isinstance(text, str) or not text.strip():
        raise UsageError("the text is empty: describe the motion, e.g. text='a person walks forward'")
    text = " ".join(text.split())
    if len(text) > MAX_TEXT_CHARS:
        raise UsageError(
            f"the text has {len(text)} characters; keep it under {MAX_TEXT_CHARS} (one motion description)"
        )
    return text


def collect_prompts(cfg: DictConfig, module: MotionDiffusionModule) -> list[str | None]:
    """The prompts to generate for: texts, action names, or [None] for unconditioned generation."""
    kind = module.condition_kind
    given = [x for x in (cfg.text, cfg.prompts, cfg.prompts_file, cfg.action) if x is not None]
    if len(given) > 1:
        raise UsageError("give only one of text=, prompts=, prompts_file= or action=")
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
        for name in names:
            if name not in module.hparams.action_names:
                raise UsageError(f"unknown action {name!r}; known actions: {', '.join(module.hparams.action_names)}")
        return names
    if cfg.prompts_file is not None:
        path = Path(cfg.prompts_file)
        if not path.is_file():
            raise UsageError(f"prompts_file {path} not found")
        texts = [line for line in path.read_text().splitlines() if line.strip()]
        if not texts:
            raise UsageError(f"prompts_file {path} has no prompts (one per line)")
    elif cfg.prompts is not None:
        texts = list(cfg.prompts) if isinstance(cfg.prompts, ListConfig | list) else [cfg.prompts]
    elif cfg.text is not None:
        texts = [cfg.text]
    else:
        raise UsageError(
            "this model is text-conditioned: pass text='a person walks forward' (or prompts=/prompts_file=)"
        )
    return [check_text(t) for t in texts]


def num_frames(cfg: DictConfig, module: MotionDiffusionModule) -> int:
    fps, max_frames = module.hparams.fps, module.hparams.max_frames
    frames = cfg.frames if cfg.frames is not None else round(float(cfg.length) * fps)
    if not isinstance(frames, int) or frames <= 0:
        raise UsageError(f"length must be positive, got {cfg.length if cfg.frames is None else cfg.frames}")
    if frames > max_frames:
        raise UsageError(
            f"{frames} frames ({frames / fps:g} s) is longer than this model's maximum of {max_frames} frames "
            f"({max_frames / fps:g} s); ask for a shorter length"
        )
    return frames


def make_condition(module: MotionDiffusionModule, prompt: str | None, n: int):
    return condition_batch(module, [prompt] * n)


def condition_batch(module: MotionDiffusionModule, conditions: list):
    """The model's condition for a batch: prompts (text models, features cached per prompt), action names or ids
    (action models), or None (unconditioned models ignore what they are given)."""
    if module.condition_kind == "text":
        from motiondiff.text.encoders import build_text_encoder

        if not hasattr(module, "_encoder"):
            module._encoder = build_text_encoder(**text_encoder_kwargs(module.hparams.text_encoder))
            module._prompt_features = {}
        new = [c for c in dict.fromkeys(conditions) if c not in module._prompt_features]
        if new:
            module._prompt_features.update(zip(new, module._encoder.encode(new).cpu(), strict=True))
        rows = torch.stack([module._prompt_features[c] for c in conditions])
        return module.prepare_text(rows.to(module.device))
    if module.condition_kind == "action":
        names = module.hparams.action_names
        ids = [c if isinstance(c, int | np.integer) else names.index(c) for c in conditions]
        return torch.tensor(ids, dtype=torch.long, device=module.device)
    return None


def slug(text: str | None) -> str:
    return re.sub(r"[^a-z0-9]+", "_", (text or "unconditioned").lower()).strip("_")[:48] or "prompt"


def run(cfg: DictConfig) -> Path:
    out = Path(HydraConfig.get().runtime.output_dir)
    ckpt = find_checkpoint(cfg.checkpoint, cfg.paths.output_dir)
    module = load_module(ckpt, cfg.device)
    prompts = collect_prompts(cfg, module)
    frames = num_frames(cfg, module)
    if cfg.num_samples < 1:
        raise UsageError(f"num_samples must be at least 1, got {cfg.num_samples}")
    guidance = module.default_guidance if cfg.guidance is None else float(cfg.guidance)
    if guidance < 0:
        raise UsageError(f"guidance must be >= 0, got {guidance}")
    steps = cfg.steps if cfg.steps is not None else cfg.sampler.steps
    if steps is not None and not 1 <= steps <= module.diffusion.num_steps:
        raise UsageError(
            f"steps must be between 1 and the model's {module.diffusion.num_steps} diffusion steps, got {steps}"
        )
    generator = torch.Generator(device=cfg.device).manual_seed(int(cfg.seed))
    results = []
    for prompt in prompts:
        cond = make_condition(module, prompt, cfg.num_samples)
        print(f"sampling {cfg.num_samples} x {frames} frames for {prompt or 'unconditioned'!r}")
        feats = module.sample(
            cond,
            torch.full((cfg.num_samples,), frames),
            guidance=guidance,
            sampler=cfg.sampler.name,
            steps=steps,
            eta=float(cfg.sampler.eta),
            generator=generator,
            progress=True,
        )
        feats = module.denormalise(feats).cpu().numpy()
        results += save_samples(out, prompt, feats, module, cfg.render)
    summary = {"checkpoint": str(ckpt), "sampler": to_dict(cfg.sampler), "guidance": guidance, "samples": results}
    (out / "results.json").write_text(json.dumps(summary, indent=1))
    print(f"\n{len(results)} sample(s) written to {out}")
    return out


def save_samples(out: Path, prompt: str | None, feats: np.ndarray, module, render: str) -> list[dict]:
    from motiondiff.export.render import render_motion

    rep = module.representation
    bridge = bridge_from_spec(module.hparams.get("representation"), module.hparams.feature_dim)
    skeleton = rep.skeleton
    fps = module.hparams.fps
    rows = []
    for k, f in enumerate(feats):
        joints = rep.decode_numpy(f).astype(np.float32)  # the representation's skeleton (a rig keeps its joints)
        stem = out / f"{slug(prompt)}_{k:02d}"
        np.save(f"{stem}_joints.npy", joints)
        np.save(f"{stem}_features.npy", f.astype(np.float32))
        video = None
        if render != "none":
            video = render_motion(joints, skeleton, f"{stem}.{render}", title=prompt or "unconditioned", fps=fps)
        feature_joints = joints if bridge.identity else bridge.joints(f)  # SMPL-22/KIT-21, what `measure` reads
        facts = measure(feature_joints, fps)
        speed = mean_joint_speed(feature_joints, fps)
        rows.append(
            {
                "prompt": prompt,
                "index": k,
                "joints": f"{stem}_joints.npy",
                "video": str(video) if video else None,
                "mean_joint_speed": speed,
                **asdict(facts),
            }  # fmt: skip
        )
    return rows
