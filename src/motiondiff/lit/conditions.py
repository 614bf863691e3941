"""A model's condition for a batch, from what a user gives: prompts (text models), action names or ids (action
models) or nothing (unconditioned models). Text features are cached on the module per prompt, and training captions
are read from the module's prepared table without an encoder."""

from __future__ import annotations

import os

import numpy as np
import torch

from motiondiff.runtime.errors import UsageError
from motiondiff.text.encoders import build_text_encoder

CLIP_PATH_ENV = "MOTIONDIFF_CLIP_PATH"  # the local CLIP folder of a model whose config names CLIP without one


def check_action(action, names: list[str], error: type[Exception] = UsageError):
    """An action the model knows, as its name or index (ids stay ints), or one clear error listing the names."""
    if isinstance(action, int | np.integer) and not isinstance(action, bool) and 0 <= int(action) < len(names):
        return int(action)
    if isinstance(action, str) and action in names:
        return action
    raise error(f"unknown action {action!r}; known actions: {', '.join(names)}")


def generation_frames(module, seconds=None, *, frames: int | None = None, name: str = "length") -> int:
    """Frames to generate for ``seconds`` (or ``frames`` as given), at least one and at most the model's maximum;
    ``name`` is what the user called the length, for the one error line."""
    fps, max_frames = float(module.hparams.fps), int(module.hparams.max_frames)
    if frames is None:
        if isinstance(seconds, bool) or not isinstance(seconds, int | float) or not np.isfinite(seconds):
            raise UsageError(f"{name} must be a number of seconds, got {seconds!r}")
        frames, given = round(float(seconds) * fps), seconds
    else:
        given = frames
        if isinstance(frames, bool) or not isinstance(frames, int | np.integer) or frames <= 0:
            raise UsageError(f"frames={frames!r}: must be a whole number of frames, at least 1 (this model makes "
                             f"{fps:g} a second; give seconds= for a length in seconds)")  # fmt: skip
    if frames <= 0:
        raise UsageError(f"{name} must be positive (at least one frame, {1 / fps:g} s), got {given!r}")
    if frames > max_frames:
        raise UsageError(
            f"{frames} frames ({frames / fps:g} s) is longer than this model's maximum of {max_frames} frames "
            f"({max_frames / fps:g} s); ask for a shorter {name}"
        )
    return int(frames)


def text_encoder_kwargs(cfg_text) -> dict:
    """Arguments of `build_text_encoder` from a text_encoder config (its `dim` is informational). A release names
    CLIP without its folder (a path in a downloaded file is never followed): that comes from $MOTIONDIFF_CLIP_PATH."""
    kwargs = {k: v for k, v in _plain(cfg_text).items() if k != "dim"}
    if kwargs.get("name") == "clip" and not kwargs.get("path"):
        path = os.environ.get(CLIP_PATH_ENV)
        if not path:
            raise UsageError(f"this model encodes text with CLIP, whose weights are not shipped: set {CLIP_PATH_ENV}="
                             "<your local clip-vit-base-patch32 folder (transformers save_pretrained)>")  # fmt: skip
        kwargs["path"] = path
    return kwargs


def _plain(cfg) -> dict:
    from omegaconf import DictConfig, OmegaConf

    return OmegaConf.to_container(cfg, resolve=True) if isinstance(cfg, DictConfig) else dict(cfg)


def condition_batch(module, conditions: list):
    """The model's condition for a batch: prompts (text models, features cached per prompt), action names or ids
    (action models), or None (unconditioned models ignore what they are given). A batch of only None asks a
    conditioned model for its ∅ condition (classifier-free guidance's unconditional half)."""
    if any(c is None for c in conditions):
        if not all(c is None for c in conditions):
            raise ValueError("a batch is conditioned or not: give a condition for every motion or for none")
        return None
    if module.condition_kind == "text":
        index = getattr(module, "text_index", {})
        if index and all(c in index for c in conditions):  # training captions (e.g. the evaluation callback's):
            rows = torch.tensor([index[c] for c in conditions], device=module.text_table.device)
            return module.text_table[rows]  # already prepared; no encoder needed
        features = prompt_features(module, conditions)
        mapping = getattr(module, "prompt_mapping", None)  # text.prompt_mapping: onto the nearest train caption
        if mapping is not None:
            features = torch.from_numpy(mapping(features.float().numpy())).to(features.dtype)
        return module.prepare_text(features.to(module.device))
    if module.condition_kind == "action":
        names = module.hparams.action_names
        ids = [c if isinstance(c, int | np.integer) else names.index(c) for c in conditions]
        return torch.tensor(ids, dtype=torch.long, device=module.device)
    return None


def prompt_features(module, prompts: list[str]) -> torch.Tensor:
    """The text encoder's features (P, E) of prompts, on the CPU; the encoder loads once and each prompt is encoded
    once per module (sampling and the coverage check share them)."""

    if not hasattr(module, "_encoder"):
        module._encoder = build_text_encoder(**text_encoder_kwargs(module.hparams.text_encoder))
        module._prompt_features = {}
    new = [c for c in dict.fromkeys(prompts) if c not in module._prompt_features]
    if new:
        module._prompt_features.update(zip(new, module._encoder.encode(new).cpu(), strict=True))
    return torch.stack([module._prompt_features[c] for c in prompts])


def repeated(module, condition, n: int):
    """The condition of one prompt, action or None for a batch of n motions."""
    return condition_batch(module, [condition] * n)
