"""Timeline mode: one motion per sample through several timed prompts, in order (`MotionPipeline.long`: each part
continues from the end of the one before)."""

from __future__ import annotations

from motiondiff.demo.inputs import DEFAULT_SAMPLING, Sampling, timeline_items
from motiondiff.demo.models import DemoModels
from motiondiff.pipelines import MotionOutput


def timeline(
    models: DemoModels, key: str, lines: str, *, seconds: float = 2.0, sampling: Sampling = DEFAULT_SAMPLING
) -> MotionOutput:
    """The timeline box's ``lines`` (``prompt : seconds`` each; ``seconds`` for a line without) as one motion per
    sample."""
    pipe = models.mdm(key, "a timeline")
    return pipe.long(timeline_items(lines, seconds), **sampling.ddim())


def segments(out: MotionOutput) -> list[tuple[str, float, float]]:
    """(label, start s, end s) of each timed prompt of a timeline's motion, for the page's timeline bar."""
    parts = (out.info.get("long_motion") or {}).get("segments") or []
    return [(str(s["label"]), s["start"] / out.fps, s["end"] / out.fps) for s in parts]
