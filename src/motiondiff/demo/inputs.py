"""The demo page's own inputs read and checked: whole numbers (Gradio numbers arrive as floats), GuidedMotion's
local-action weights, the prompt of a text or an action model, the kept share of an in-between and the lines of a
timeline. Each mistake is one UsageError that names the fix; no web code here."""

from __future__ import annotations

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
