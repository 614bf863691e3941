"""File names of saved motions, one scheme for the commands and the Python API: `<prompt slug>_<k>` where k counts
the motions of that prompt (`a_person_walks_forward_00`, `_01`, ...; `unconditioned_00` without a prompt)."""

from __future__ import annotations

import re


def slug(text: str | None) -> str:
    """A prompt as a file-name stem: lower-case letters and digits joined by `_`, at most 48 characters."""
    return re.sub(r"[^a-z0-9]+", "_", (text or "unconditioned").lower()).strip("_")[:48] or "prompt"


def unique_stems(prompts: list[str | None]) -> list[str]:
    """One file stem per prompt, distinct even where prompts slug alike (emoji-only text, the same first 48
    characters): the second gets ``_2``, the third ``_3``, ... so no prompt's files overwrite another's."""
    taken: set[str] = set()
    stems = []
    for prompt in prompts:
        base = stem = slug(prompt)
        n = 1
        while stem in taken:
            n += 1
            stem = f"{base}_{n}"
        taken.add(stem)
        stems.append(stem)
    return stems


def motion_stems(prompts: list[str | None], prefix: str = "") -> list[str]:
    """The stem of each motion of a batch whose i-th motion was made from ``prompts[i]``: ``prefix`` (``long_`` for
    one motion through several prompts), its prompt's unique stem and its number among that prompt's motions."""
    distinct = list(dict.fromkeys(prompts))
    stem_of = dict(zip(distinct, unique_stems(distinct), strict=True))
    counts: dict = {}
    stems = []
    for prompt in prompts:
        k = counts.get(prompt, 0)
        counts[prompt] = k + 1
        stems.append(f"{prefix}{stem_of[prompt]}_{k:02d}")
    return stems
