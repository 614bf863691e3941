"""Broad wording for GENERATED captions (`--caption-wording broad`): the mess of how people actually write.

Human caption corpora mix the action with context that does not change it ("... then stops", "from a standing
position, ..."), capitalise or not, drop the full stop and misspell words. A model trained only on clean templates
reads any of these as a new sentence. `broaden` adds them to a generated sentence at random, so training sees them;
it never touches the words that carry left and right (the mirror augmentation swaps those) or the action's own words
beyond one letter swap. Hand-written rather than a text-augmentation library: the few edits needed must leave side
words intact, which general augmenters do not guarantee.
"""

from __future__ import annotations

import numpy as np

# Clauses that add context without changing the motion (none names a side, a direction or a body part).
TAILS = (
    "then stops",
    "and then stands still",
    "then comes to a stop",
    "and stops afterwards",
    "before standing still again",
    "for a few seconds",
    "and then holds still for a moment",
    "then goes back to standing",
)
LEADS = ("from a standing position, ", "after standing for a moment, ", "in this clip, ", "at one point, ")
_KEEP = {"left", "right", "both", "backward", "backwards", "forward"}  # never misspelt: they carry the meaning


def broaden(sentence: str, rng: np.random.Generator, context: float = 0.4, noise: float = 0.3) -> str:
    """`sentence` (one generated caption ending in '.') with, at random: a context clause (probability `context`:
    three in four a tail clause, else a lead-in), then surface noise (probability `noise`: one adjacent-letter swap
    in a word of 5+ letters other than side and direction words, a missing full stop, or a capital first letter)."""
    text = sentence.rstrip(".")
    if rng.random() < context:
        if rng.random() < 0.75:
            text = f"{text}, {rng.choice(TAILS)}"
        else:
            text = f"{rng.choice(LEADS)}{text}"
    text += "."
    if rng.random() < noise:
        kind = int(rng.integers(3))
        if kind == 0:
            text = _swap_letters(text, rng)
        elif kind == 1:
            text = text.rstrip(".")
        else:
            text = text[:1].upper() + text[1:]
    return text


def _swap_letters(text: str, rng: np.random.Generator) -> str:
    """Swap two adjacent inner letters of one word of 5+ letters ("raises" -> "riases"); unchanged if none fits."""
    words = text.split(" ")
    cores = [w.strip(".,") for w in words]
    fits = [i for i, c in enumerate(cores) if len(c) >= 5 and c.isalpha() and c.lower() not in _KEEP]
    if not fits:
        return text
    i = int(rng.choice(fits))
    w = words[i]
    j = int(rng.integers(1, len(cores[i]) - 2))  # an inner pair: the first and last letters stay
    words[i] = w[:j] + w[j + 1] + w[j] + w[j + 2 :]
    return " ".join(words)
