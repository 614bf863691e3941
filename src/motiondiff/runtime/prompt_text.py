"""A user's prompt checked as text (no model needed, nothing heavy imported): the commands and the Python API refuse
an empty, invisible or overlong prompt, and read a timed prompt ("a person walks:4") the same way, before any model
loads."""

from __future__ import annotations

import math
import re
import unicodedata

from motiondiff.runtime.errors import UsageError
from motiondiff.runtime.settings import MAX_LONG_SECONDS, MAX_SEGMENT_SECONDS, MAX_TEXT_CHARS

# "<text>:<seconds>", seconds a decimal (optionally "4s"), inf or nan; a colon not followed by a number is text
TIMED = re.compile(
    r"^(?P<text>.*?)\s*:\s*(?P<seconds>[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?inf(?:inity)?|nan)\s*s?\s*$",
    re.IGNORECASE,
)


def check_text(text) -> str:
    """A prompt with its whitespace tidied and invisible format characters (zero-width spaces, direction marks)
    removed, or one clear error for a prompt that is not text, is empty, or is overlong."""
    if not isinstance(text, str):
        raise UsageError(f"a prompt must be text, got {type(text).__name__}: pass a string such as 'a person walks'")
    text = "".join(c for c in text if unicodedata.category(c) not in ("Cf", "Cc") or c in "\t\n\r")
    if not text.strip():
        raise UsageError("the text is empty: describe the motion, e.g. text='a person walks forward'")
    text = " ".join(text.split())
    if len(text) > MAX_TEXT_CHARS:
        raise UsageError(
            f"the text has {len(text)} characters; keep it under {MAX_TEXT_CHARS} (one motion description)"
        )
    return text


def split_time(item) -> tuple[str, float | None]:
    """("a person walks", 4.0) for "a person walks:4", (item, None) for a prompt with no time; a time that is not a
    positive number of seconds up to MAX_SEGMENT_SECONDS, or one with no text before it, is one UsageError."""
    m = TIMED.match(item) if isinstance(item, str) else None
    if m is None:
        return item, None
    text, seconds = m["text"].strip(), float(m["seconds"])
    if not text:
        raise UsageError(f"{item!r} has a time but no prompt before the colon")
    if not (math.isfinite(seconds) and 0 < seconds <= MAX_SEGMENT_SECONDS):
        raise UsageError(f"{item!r}: the seconds after the colon must be a number in (0, {MAX_SEGMENT_SECONDS:g}]")
    return text, seconds


def check_long_seconds(seconds) -> None:
    """A long motion's total length within MAX_LONG_SECONDS, refused before any sampling."""
    total = float(sum(seconds))
    if total > MAX_LONG_SECONDS:
        raise UsageError(f"the timed prompts add up to {total:g} s; one long motion is at most {MAX_LONG_SECONDS:g} s: "
                         "shorten them or make several motions")  # fmt: skip
