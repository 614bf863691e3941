"""Timeline mode: one motion per sample through several timed prompts, in order (`MotionPipeline.long`: each part
continues from the end of the one before)."""

from __future__ import annotations

from motiondiff.demo.inputs import steps_of, timeline_items, whole
from motiondiff.demo.models import MAX_SAMPLES, DemoModels
from motiondiff.pipelines import MotionOutput


def timeline(
    models: DemoModels,
    key: str,
    lines: str,
    *,
    seconds: float = 2.0,
    seed: int = 0,
    steps: int | None = None,
    guidance: float | None = None,
    num_samples: int = 1,
) -> MotionOutput:
    """The timeline box's ``lines`` (``prompt : seconds`` each; ``seconds`` for a line without) as one motion."""
    pipe = models.mdm(key, "a timeline")
    count = whole(num_samples, "number of samples", 1, MAX_SAMPLES)
    return pipe.long(timeline_items(lines, seconds), num_samples=count,
                     seed=whole(seed, "seed", 0, 2**63 - 1), sampler="ddim", steps=steps_of(steps),
                     guidance=guidance)  # fmt: skip


def segments(out: MotionOutput) -> list[tuple[str, float, float]]:
    """(label, start s, end s) of each timed prompt of a timeline's motion, for the page's timeline bar."""
    parts = (out.info.get("long_motion") or {}).get("segments") or []
    return [(str(s["label"]), s["start"] / out.fps, s["end"] / out.fps) for s in parts]
