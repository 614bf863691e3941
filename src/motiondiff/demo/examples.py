"""Example prompts the page offers, taken from what the loaded model was trained on rather than a fixed list.

A text release carries its prompt-coverage bank, which names the actions of its training captions; each becomes a
prompt through the phrase table its captions were written with (`data.preparing.captions.CONTENT_PHRASES`), so an
example is in-domain by construction. An action model's examples are its action names. GuidedMotion, which steers
each verb of one caption as a local action, gets COMPOUND captions of two to three actions. A text model released
without a bank gets FALLBACK. Timelines chain three of the examples.
"""

from __future__ import annotations

from motiondiff.data.preparing.captions import CONTENT_PHRASES

FALLBACK = ("a person walks forward", "a person waves the right hand", "a person bows")
COMPOUND = ("a person walks forward, then raises both hands", "a person waves the right hand, then bows",
            "a person walks forward, then turns left, and then runs")  # fmt: skip
TIMELINE_SECONDS = 2  # each example timeline line's length
TIMELINE_EXAMPLES = 3


def action_prompt(name: str) -> str:
    """A training action as a caption-style prompt ("wave-right-hand" -> "a person waves the right hand")."""
    return f"a person {CONTENT_PHRASES.get(name, name.replace('-', ' '))}"


def example_prompts(pipe) -> list[str]:
    """The prompts (or action names) to offer for ``pipe`` (a MotionPipeline, or any pipeline: FALLBACK)."""
    kind = getattr(pipe, "condition_kind", None)
    if hasattr(pipe, "latent"):  # GuidedMotionPipeline: one caption, several local actions
        return list(COMPOUND)
    if kind == "action":
        return list(pipe.actions)
    coverage = getattr(pipe, "coverage", None)
    names = list(coverage.action_names) if coverage is not None else []
    return [action_prompt(n) for n in names] or list(FALLBACK)


def example_timelines(examples: list[str], count: int = TIMELINE_EXAMPLES) -> list[str]:
    """``count`` timelines of three examples each (spread over the list, so they differ), one ``prompt : seconds``
    per line."""
    if not examples:
        return []
    n, stride = len(examples), max(1, len(examples) // 3)
    timelines = []
    for k in range(count):
        picks = list(dict.fromkeys(examples[(k + j * stride) % n] for j in range(3)))
        timelines.append("\n".join(f"{p} : {TIMELINE_SECONDS}" for p in picks))
    return list(dict.fromkeys(timelines))
