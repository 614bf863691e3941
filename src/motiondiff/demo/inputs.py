"""The demo page's own inputs read and checked: whole numbers (Gradio numbers arrive as floats), the sampling
settings every mode shares, GuidedMotion's local-action weights, the kept share of an in-between and the lines of a
timeline. Each mistake is one UsageError that names the fix; no web code here."""

from __future__ import annotations

from dataclasses import dataclass

from motiondiff.demo.models import MAX_SAMPLES
from motiondiff.runtime.errors import UsageError
from motiondiff.runtime.prompt_text import split_time


def whole(value, name: str, low: int, high: int) -> int:
    """A whole number from the page in ``low..high``."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise UsageError(f"{name} must be a whole number, got {value!r}") from None
    if not number.is_integer() or not low <= number <= high:
        raise UsageError(f"{name} must be a whole number in {low}..{high}, got {value!r}")
    return int(number)


def steps_of(value) -> int | None:
    """The sampler steps box: empty means the model's default."""
    return None if value in (None, "") else whole(value, "steps", 1, 10_000)


@dataclass(frozen=True)
class Sampling:
    """The sampling settings of every mode: ``num_samples`` motions from ``seed`` with DDIM ``steps`` and
    ``guidance`` (None: the model's defaults). `from_page` reads and checks the page's boxes once."""

    seed: int = 0
    steps: int | None = None
    guidance: float | None = None
    num_samples: int = 1

    @classmethod
    def from_page(cls, seed=0, steps=None, guidance=None, num_samples=1) -> Sampling:
        """The settings as the page's boxes give them (floats for whole numbers, an empty steps box)."""
        return cls(whole(seed, "seed", 0, 2**63 - 1), steps_of(steps), guidance,
                   whole(num_samples, "number of samples", 1, MAX_SAMPLES))  # fmt: skip

    def ddim(self) -> dict:
        """The keywords of the `MotionPipeline` calls (`__call__`, `edit_parts`, `inbetween`, `long`): DDIM."""
        return {"num_samples": self.num_samples, "seed": self.seed, "sampler": "ddim", "steps": self.steps,
                "guidance": self.guidance}  # fmt: skip


DEFAULT_SAMPLING = Sampling()  # one motion from seed 0 with the model's own steps and guidance


def parse_weights(text: str | None) -> list[float] | None:
    """GuidedMotion's local-action weights from the page: "2, 0.5" (one per local action); empty: None (1 each)."""
    if text is None or not str(text).strip():
        return None
    try:
        return [float(w) for w in str(text).replace(";", ",").split(",") if w.strip()]
    except ValueError:
        raise UsageError(
            f"local action weights must be numbers separated by commas, e.g. 2, 0.5; got {text!r}"
        ) from None


def share(percent, name: str) -> float:
    """A percentage of the motion (0..50, the in-between's kept start or end) as the fraction the API takes."""
    try:
        value = float(percent)
    except (TypeError, ValueError):
        raise UsageError(f"{name} must be a percentage from 0 to 50, got {percent!r}") from None
    if not 0 <= value <= 50:
        raise UsageError(f"{name} must be a percentage from 0 to 50, got {percent!r}")
    return value / 100.0


def timeline_items(text: str | None, default_seconds: float) -> list[str]:
    """The timeline box, one ``prompt : seconds`` per line (a line without seconds lasts ``default_seconds``), as the
    "text:seconds" items `MotionPipeline.long` takes; blank lines are skipped."""
    lines = [line.strip() for line in str(text or "").splitlines() if line.strip()]
    if not lines:
        raise UsageError("the timeline is empty: write one prompt per line with its seconds, e.g. 'a person walks : 2' "
                         "then 'a person waves the right hand : 2'")  # fmt: skip
    items = []
    for line in lines:
        prompt, seconds = split_time(line)
        items.append(f"{prompt}:{seconds if seconds is not None else float(default_seconds):g}")
    return items
