"""Config values checked before any work starts: wrong types and out-of-range numbers fail with the key path and
the allowed range, not deep inside PyTorch after files were written.

Hydra's structured configs (dataclasses in a ConfigStore) would type every key, but these configs are mostly open
groups (any backbone or dataset brings its own keys); a rule table over the keys every run shares checks types and
ranges in one place, and the entry points call `check(cfg, RULES_...)` first. Every number of a config, ruled or
not, must be finite: ``guidance=nan`` would otherwise sample NaN motions and write them.
"""

from __future__ import annotations

import math

from omegaconf import DictConfig, OmegaConf

from motiondiff.runtime.errors import UsageError
from motiondiff.runtime.settings import EVALUATION, GENERATION, POSITIVE_INT, SEED, Rule


def _representations() -> tuple:
    from motiondiff.data.representations import REPRESENTATIONS  # scipy and torch: not for the commands' first check

    return tuple(REPRESENTATIONS)


COMMON = {"seed": SEED, "paths.output_dir": Rule(str)}
MODEL = {"model.d_model": POSITIVE_INT, "model.num_layers": POSITIVE_INT, "model.num_heads": POSITIVE_INT,
         "model.ff_size": POSITIVE_INT, "model.dropout": Rule(float, low=0, below=1)}  # fmt: skip
RULES_TRAIN = {
    **COMMON, **MODEL,
    "batch_size": POSITIVE_INT, "num_workers": Rule(int, low=0), "checkpoint_every": POSITIVE_INT,
    "optim.lr": Rule(float, above=0), "optim.weight_decay": Rule(float, low=0), "optim.warmup_steps": Rule(int, low=0),
    "trainer.max_steps": Rule(int, low=-1), "trainer.gradient_clip_val": Rule(float, low=0, optional=True),
    "diffusion.steps": POSITIVE_INT, "condition.drop_prob": Rule(float, low=0, high=1),
    "dataset.datamodule.max_frames": Rule(int, low=1, optional=True), "ema_decay": Rule(float, low=0, below=1),
    "representation": Rule(str, choices=_representations, optional=True),
}  # fmt: skip
# Types, finiteness and plain ranges here, before the model loads; length, frames and steps are checked again by
# sample/edit against the loaded model (its maximum length and diffusion steps), with messages that say so.
_SAMPLING = ("guidance", "steps", "length", "frames", "overlap", "blend", "smooth_sigma", "resample")
RULES_SAMPLE = {
    **COMMON,
    **{key: GENERATION[key] for key in _SAMPLING},
    "sampler.eta": GENERATION["eta"],
    "num_samples": POSITIVE_INT,
}  # its upper bound: lit.generation.check_num_samples, as the API's
RULES_EDIT = {
    **RULES_SAMPLE, "start": Rule(float, low=0), "prefix": Rule(float, low=0), "suffix": Rule(float, low=0),
    "prefix_s": Rule(float, low=0, optional=True), "suffix_s": Rule(float, low=0, optional=True),
    "hold_from": Rule(float, above=0, high=1), "reconstruction": Rule(float, low=0),
    "boundary_blend": Rule(int, low=0),
}  # fmt: skip
RULES_EVALUATE = {
    **COMMON, **EVALUATION, "guidance": GENERATION["guidance"], "steps": GENERATION["steps"],
    "split": Rule(str, choices=("train", "val", "test")),
    "evaluator": Rule(str, choices=("released", "official")),
    "prompt_mapping": Rule(str, choices=("none", "nearest", "vote")),  # text.prompt_mapping.MODES; importing
    # motiondiff.text would load the encoders (1.5 s) before any check (tests/unit/text/test_prompt_mapping.py)
}  # fmt: skip


def non_finite(value, key: str = ""):
    """(key, value) of the first NaN or infinite float in a plain config tree, None when every number is finite."""
    from motiondiff.runtime.scripting import USER_TEXT_KEYS  # here: scripting is the commands' module, not the rules'

    if isinstance(value, float) and not math.isfinite(value):
        return key, value
    items = value.items() if isinstance(value, dict) else enumerate(value) if isinstance(value, list) else ()
    for k, v in items:
        if not key and k in USER_TEXT_KEYS:  # user text is data (text=nan is the text "nan", checked as text)
            continue
        found = non_finite(v, f"{key}[{k}]" if isinstance(k, int) else f"{key}.{k}" if key else str(k))
        if found is not None:
            return found
    return None


def check_finite(cfg: DictConfig) -> None:
    """Raise UsageError naming the first setting that is NaN or infinite (read unresolved: nothing is evaluated)."""
    found = non_finite(OmegaConf.to_container(cfg, resolve=False))
    if found is not None:
        key, value = found
        raise UsageError(f"{key}={value}: must be a finite number (not nan or inf); fix it with {key}=<number>")


def check(cfg: DictConfig, rules: dict[str, Rule]) -> None:
    """Raise UsageError naming the first key whose value breaks its rule (keys a config lacks are skipped), or the
    first number anywhere in the config that is NaN or infinite."""
    for key, rule in rules.items():
        if OmegaConf.select(cfg, key, default="__missing__", throw_on_missing=False) == "__missing__":
            continue
        value = OmegaConf.select(cfg, key)
        if rule.kind is str and not rule.choices:
            if not isinstance(value, str) or not value.strip():
                raise UsageError(f"{key}={value!r}: must be a non-empty string")
            continue
        rule.check(key, value)
    d_model, heads = OmegaConf.select(cfg, "model.d_model"), OmegaConf.select(cfg, "model.num_heads")
    if isinstance(d_model, int) and isinstance(heads, int) and d_model % heads:
        raise UsageError(f"model.num_heads={heads} must divide model.d_model={d_model} (each head gets d_model/heads "
                         "dims); e.g. model.num_heads=4")  # fmt: skip
    check_finite(cfg)
