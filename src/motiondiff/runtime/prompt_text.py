"""A user's prompt checked as text (no model needed, nothing heavy imported): the commands refuse an empty or
overlong prompt before they load a model."""

from __future__ import annotations

from motiondiff.runtime.errors import UsageError

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
