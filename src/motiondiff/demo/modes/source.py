"""The motion an edit or an in-between starts from: one sample of the page's last result, or an uploaded file
(BVH, joints .npy/.npz), as `MotionPipeline.edit_parts` / `inbetween` take it."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from motiondiff.demo.inputs import whole
from motiondiff.pipelines import MotionOutput
from motiondiff.runtime.errors import UsageError

ON_PAGE = "a sample on the page"
UPLOADED = "an uploaded file"
SOURCES = (ON_PAGE, UPLOADED)


def motion_source(source: str, last: MotionOutput | None, sample, upload: str | None) -> MotionOutput | str:
    """Sample ``sample`` (1-based) of ``last``, or the ``upload``'s path, by ``source``."""
    if source == UPLOADED:
        if not upload:
            raise UsageError("upload a motion first (a .bvh, or joints as .npy/.npz), or start from a sample on the "
                             "page")  # fmt: skip
        return str(Path(upload))
    if source != ON_PAGE:
        raise UsageError(f"start from one of: {', '.join(SOURCES)}; got {source!r}")
    if last is None:
        raise UsageError("generate a motion first (or upload one): the edit starts from a sample on the page")
    k = whole(sample, "sample", 1, len(last)) - 1
    return replace(last, joints=[last.joints[k]], features=[last.features[k]], prompts=[last.prompts[k]], edit=None,
                   source=None)  # fmt: skip
