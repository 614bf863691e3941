"""In-between mode: keep the first and last part of a motion (an uploaded BVH, or a sample on the page) and generate
the frames between from a prompt (MDM's in-betweening, `MotionPipeline.inbetween`)."""

from __future__ import annotations

from dataclasses import replace

from motiondiff.demo.inputs import DEFAULT_SAMPLING, Sampling, share
from motiondiff.demo.models import DemoModels
from motiondiff.pipelines import MotionOutput


def inbetween(
    models: DemoModels,
    key: str,
    motion: MotionOutput | str,
    prompt: str | None,
    *,
    keep_start: float = 25,
    keep_end: float = 25,
    sampling: Sampling = DEFAULT_SAMPLING,
) -> MotionOutput:
    """``sampling.num_samples`` in-betweens of ``motion`` keeping ``keep_start`` and ``keep_end`` percent of its
    frames."""
    pipe = models.mdm(key, "in-betweening")
    out = pipe.inbetween(motion, prompt or None, prefix=share(keep_start, "kept start"),
                         suffix=share(keep_end, "kept end"), **sampling.ddim())  # fmt: skip
    return replace(out, edit=None)
