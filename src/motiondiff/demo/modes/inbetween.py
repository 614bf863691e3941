"""In-between mode: keep the first and last part of a motion (an uploaded BVH, or a sample on the page) and generate
the frames between from a prompt (MDM's in-betweening, `MotionPipeline.inbetween`)."""

from __future__ import annotations

from dataclasses import replace

from motiondiff.demo.inputs import share, steps_of, whole
from motiondiff.demo.models import MAX_SAMPLES, DemoModels
from motiondiff.pipelines import MotionOutput


def inbetween(
    models: DemoModels,
    key: str,
    motion: MotionOutput | str,
    prompt: str | None,
    *,
    keep_start: float = 25,
    keep_end: float = 25,
    seed: int = 0,
    steps: int | None = None,
    guidance: float | None = None,
    num_samples: int = 1,
) -> MotionOutput:
    """``num_samples`` in-betweens of ``motion`` keeping ``keep_start`` and ``keep_end`` percent of its frames."""
    pipe = models.mdm(key, "in-betweening")
    out = pipe.inbetween(motion, prompt or None, prefix=share(keep_start, "kept start"),
                         suffix=share(keep_end, "kept end"),
                         num_samples=whole(num_samples, "number of samples", 1, MAX_SAMPLES),
                         seed=whole(seed, "seed", 0, 2**63 - 1), sampler="ddim", steps=steps_of(steps),
                         guidance=guidance)  # fmt: skip
    return replace(out, edit=None)
