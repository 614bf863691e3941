"""A model's condition for a batch, from what a user gives: prompts (text models), action names or ids (action
models) or nothing (unconditioned models). Text features are cached on the module per prompt, and training captions
are read from the module's prepared table without an encoder."""

from __future__ import annotations

import numpy as np
import torch

from motiondiff.errors import UsageError

MAX_TEXT_CHARS = 1000  # far beyond any caption the encoders were trained on (CLIP keeps 77 tokens)


def check_text(text) -> str:
    """A prompt with its whitespace tidied, or one clear error for an empty or overlong one."""
    if not isinstance(text, str) or not text.strip():
        raise UsageError("the text is empty: describe the motion, e.g. text='a person walks forward'")
    text = " ".join(text.split())
    if len(text) > MAX_TEXT_CHARS:
        raise UsageError(
            f"the text has {len(text)} characters; keep it under {MAX_TEXT_CHARS} (one motion description)"
        )
    return text


def text_encoder_kwargs(cfg_text) -> dict:
    """Arguments of `build_text_encoder` from a text_encoder config (its `dim` is informational)."""
    return {k: v for k, v in _plain(cfg_text).items() if k != "dim"}


def _plain(cfg) -> dict:
    from omegaconf import DictConfig, OmegaConf

    return OmegaConf.to_container(cfg, resolve=True) if isinstance(cfg, DictConfig) else dict(cfg)


def condition_batch(module, conditions: list):
    """The model's condition for a batch: prompts (text models, features cached per prompt), action names or ids
    (action models), or None (unconditioned models ignore what they are given)."""
    if module.condition_kind == "text":
        from motiondiff.text.encoders import build_text_encoder

        index = getattr(module, "text_index", {})
        if index and all(c in index for c in conditions):  # training captions (e.g. the evaluation callback's):
            rows = torch.tensor([index[c] for c in conditions], device=module.text_table.device)
            return module.text_table[rows]  # already prepared; no encoder needed
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


def repeated(module, condition, n: int):
    """The condition of one prompt, action or None for a batch of n motions."""
    return condition_batch(module, [condition] * n)
