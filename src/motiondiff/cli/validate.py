"""Config values checked before any work starts: wrong types and out-of-range numbers fail with the key path and
the allowed range, not deep inside PyTorch after files were written.

Hydra's structured configs (dataclasses in a ConfigStore) would type every key, but these configs are mostly open
groups (any backbone or dataset brings its own keys); a rule table over the keys every run shares checks types and
ranges in one place, and the entry points call `check(cfg, RULES_...)` first. Every number of a config, ruled or
not, must be finite: ``guidance=nan`` would otherwise sample NaN motions and write them.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from omegaconf import DictConfig, OmegaConf

from motiondiff.runtime.errors import UsageError


def _first(*values):
    return next((v for v in values if v is not None), None)


def _number(bound: float) -> str:
    return str(bound) if isinstance(bound, int) else f"{bound:g}"  # an integer prints whole (2**63-1, not 9.2e+18)


@dataclass(frozen=True)
class Rule:
    kind: type  # int or float (an int passes as a float); str for a choice
    low: float | None = None  # inclusive
    above: float | None = None  # exclusive lower bound
    high: float | None = None  # inclusive
    below: float | None = None  # exclusive upper bound
    choices: tuple | Callable[[], tuple] | None = None  # a callable is asked when checking (heavy imports)
    optional: bool = False  # null allowed

    @property
    def options(self) -> tuple | None:
        return self.choices() if callable(self.choices) else self.choices

    def describe(self) -> str:
        if self.choices:
            return "one of " + ", ".join(map(str, self.options))
        parts = ["an integer" if self.kind is int else "a number"]
        lower, upper = _first(self.low, self.above), _first(self.high, self.below)
        if lower is not None and upper is not None:  # a two-sided range as an interval: "in (0, 1]"
            left, right = "[" if self.low is not None else "(", "]" if self.high is not None else ")"
            parts.append(f"in {left}{_number(lower)}, {_number(upper)}{right}")
            return " ".join(parts) + (" (or null)" if self.optional else "")
        for sign, bound in ((">=", self.low), (">", self.above), ("<=", self.high), ("<", self.below)):
            if bound is not None:
                parts.append(f"{sign} {_number(bound)}")
        return " ".join(parts) + (" (or null)" if self.optional else "")

    def accepts(self, value) -> bool:
        if value is None:
            return self.optional
        if self.choices:
            return value in self.options
        if isinstance(value, bool) or not isinstance(value, int | float):
            return False
        if self.kind is int and not isinstance(value, int):
            return False
        if not math.isfinite(value):
            return False
        return ((self.low is None or value >= self.low) and (self.above is None or value > self.above)
                and (self.high is None or value <= self.high)
                and (self.below is None or value < self.below))  # fmt: skip


def _representations() -> tuple:
    from motiondiff.data.representations import REPRESENTATIONS  # scipy and torch: not for the commands' first check

    return tuple(REPRESENTATIONS)


POSITIVE_INT = Rule(int, low=1)
SEED = Rule(int, low=0, high=2**63 - 1)  # torch.Generator.manual_seed takes at most 64 bits
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
RULES_SAMPLE = {
    **COMMON, "num_samples": POSITIVE_INT, "length": Rule(float, above=0, optional=True),
    "frames": Rule(int, low=1, optional=True), "steps": Rule(int, low=1, optional=True),
    "overlap": Rule(float, low=0), "blend": Rule(float, low=0), "smooth_sigma": Rule(float, low=0, optional=True),
}  # fmt: skip
RULES_EDIT = {
    **RULES_SAMPLE, "start": Rule(float, low=0), "prefix": Rule(float, low=0), "suffix": Rule(float, low=0),
    "prefix_s": Rule(float, low=0, optional=True), "suffix_s": Rule(float, low=0, optional=True),
    "hold_from": Rule(float, above=0, high=1), "reconstruction": Rule(float, low=0), "resample": POSITIVE_INT,
    "boundary_blend": Rule(int, low=0),
}  # fmt: skip
RULES_EVALUATE = {
    **COMMON, "replications": POSITIVE_INT, "mm_replications": Rule(int, low=0), "guidance": Rule(float, low=0, optional=True),
    "steps": Rule(int, low=1, optional=True), "batch_size": POSITIVE_INT,
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
        if not rule.accepts(value):
            raise UsageError(f"{key}={value!r}: must be {rule.describe()}; fix it with {key}=<value>")
    d_model, heads = OmegaConf.select(cfg, "model.d_model"), OmegaConf.select(cfg, "model.num_heads")
    if isinstance(d_model, int) and isinstance(heads, int) and d_model % heads:
        raise UsageError(f"model.num_heads={heads} must divide model.d_model={d_model} (each head gets d_model/heads "
                         "dims); e.g. model.num_heads=4")  # fmt: skip
    check_finite(cfg)
