"""Edit mode: regenerate body parts of a motion from a prompt and keep the rest of the body. ``parts`` names the parts
that are REGENERATED, as `edit.py parts=` and `MotionPipeline.edit_parts(parts=)` do."""

from __future__ import annotations

from dataclasses import replace

from motiondiff.demo.inputs import DEFAULT_SAMPLING, Sampling
from motiondiff.demo.models import DemoModels
from motiondiff.pipelines import MotionOutput
from motiondiff.runtime.errors import UsageError


def edit_parts(
    models: DemoModels,
    key: str,
    motion: MotionOutput | str,
    prompt: str | None,
    parts,
    *,
    sampling: Sampling = DEFAULT_SAMPLING,
) -> MotionOutput:
    """``sampling.num_samples`` edits of ``motion`` (one motion, or a file path) with ``parts`` regenerated from
    ``prompt``."""
    pipe = models.mdm(key, "body-part editing")
    if not parts:
        raise UsageError(
            f"choose the body parts to regenerate: {', '.join(sorted(pipe.model.representation.skeleton.parts))}"
        )
    out = pipe.edit_parts(motion, prompt or None, parts=parts if isinstance(parts, str) else list(parts),
                          **sampling.ddim())  # fmt: skip
    return replace(out, edit=None)  # saved as plain motions: the page shows the edits, not the input again
