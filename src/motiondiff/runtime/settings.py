"""The settings a user types by hand, and how much work one request may ask for, as one table: the commands (through
`cli.validate`), the Python API (`pipelines`) and the demo check against it before any work starts, so a value
refused on one surface is refused on every one, in the same words, with the limit and the fix named.

Hydra's structured configs would type the commands' keys, but not the API's keywords; one rule table serves both.
Nothing heavy is imported here (the commands check before torch loads).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable
from dataclasses import dataclass

from motiondiff.runtime.errors import UsageError

# ---- bounds: how much one request may ask for (each refused before any work, with the limit named) ---------------
MAX_TEXT_CHARS = 1000  # one prompt: far beyond any caption the encoders were trained on (CLIP keeps 77 tokens)
MAX_NUM_SAMPLES = 1000  # motions per prompt (or per edited motion) in one request
MAX_PROMPTS = 256  # prompts (action labels) in one request: with MAX_NUM_SAMPLES, 256,000 motions at most
MAX_SEGMENTS = 64  # timed prompts of one long motion
MAX_SEGMENT_SECONDS = 120.0  # one timed prompt of a long motion
MAX_LONG_SECONDS = 600.0  # one long motion in all (12,000 frames at 20 fps)
MAX_REPLICATIONS = 100  # evaluate.py (the protocol's 20; 100 for a fifth of their CI width)
MAX_BATCH_SIZE = 4096  # motions generated or scored per batch
MAX_PROMPTS_FILE_BYTES = 1 << 20  # a prompts file (1 MiB: over 10,000 prompts); larger ones are refused unread
MAX_SWEEP_JOBS = 1000  # jobs of one Hydra multirun (-m): a typo such as range(0,1000000) is refused at once
MIN_FREE_BYTES = 1 << 20  # free space a run folder's disk needs before Hydra writes its config and log there


def _first(*values):
    return next((v for v in values if v is not None), None)


def _number(bound: float) -> str:
    return str(bound) if isinstance(bound, int) else f"{bound:g}"  # an integer prints whole (2**63-1, not 9.2e+18)


@dataclass(frozen=True)
class Rule:
    """What one setting may be: a whole number or a number in a range (finite; a bool is neither), or a choice."""

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
            return isinstance(value, str) and value in self.options
        # numpy scalars are numbers too (numbers.Integral / numbers.Real); a bool is neither here
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            return False
        if self.kind is int and not isinstance(value, numbers.Integral):
            return False
        if not math.isfinite(value):
            return False
        return ((self.low is None or value >= self.low) and (self.above is None or value > self.above)
                and (self.high is None or value <= self.high)
                and (self.below is None or value < self.below))  # fmt: skip

    def check(self, name: str, value):
        """``value`` as a plain int/float (or the choice, or None), else one UsageError naming the rule and the fix."""
        if not self.accepts(value):
            raise UsageError(f"{name}={value!r}: must be {self.describe()}; fix it with {name}=<value>")
        if value is None or self.choices:
            return value
        return int(value) if self.kind is int else float(value)


POSITIVE_INT = Rule(int, low=1)
SEED = Rule(int, low=0, high=2**63 - 1)  # torch.Generator.manual_seed takes at most 64 bits

# The generation settings every surface shares (keyword = config key). Lengths and steps are checked again against
# the loaded model (its maximum length, its diffusion steps), with messages that say so; num_samples (1 to
# MAX_NUM_SAMPLES, or one batch for long motions) by `lit.generation.check_num_samples`.
GENERATION = {
    "seed": SEED,
    "guidance": Rule(float, low=0, optional=True),
    "steps": Rule(int, low=1, optional=True),
    "eta": Rule(float, low=0, high=1),
    "smooth_sigma": Rule(float, low=0, optional=True),
    "seconds": Rule(float, above=0, high=MAX_SEGMENT_SECONDS),
    "length": Rule(float, above=0, optional=True),  # at most the model's own length: checked with the model
    "frames": Rule(int, low=1, optional=True),
    "overlap": Rule(float, low=0),  # > 0 for a long motion: checked with the model (edit.long_motion)
    "blend": Rule(float, low=0),
    "resample": POSITIVE_INT,
}
EVALUATION = {
    "replications": Rule(int, low=1, high=MAX_REPLICATIONS),
    "mm_replications": Rule(int, low=0, high=MAX_REPLICATIONS),
    "batch_size": Rule(int, low=1, high=MAX_BATCH_SIZE),
}


def check_settings(table: dict[str, Rule] = GENERATION, **values) -> dict:
    """Each keyword checked by its rule in ``table`` (first failure: one UsageError); the values as plain numbers."""
    return {name: table[name].check(name, value) for name, value in values.items()}


def check_count(what: str, count: int, limit: int, fix: str) -> None:
    """Refuse a request of more than ``limit`` ``what`` before any work, naming the limit and ``fix``."""
    if count > limit:
        raise UsageError(f"{count} {what} in one request; at most {limit}: {fix}")
