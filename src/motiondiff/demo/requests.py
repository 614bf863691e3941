"""One demo request from start to files, without web code: run a mode in its own request folder
(`request_folders`), write each motion's files and a zip of them all (`files`), and collect the prompt-coverage
warnings the pipeline raised (`PromptCoverageWarning`: a prompt far from the model's training captions)."""

from __future__ import annotations

import contextlib
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from motiondiff.demo.files import Sample, write_samples, zip_folder
from motiondiff.demo.models import DemoModels
from motiondiff.demo.request_folders import request_folder
from motiondiff.pipelines import MotionOutput
from motiondiff.pipelines.coverage import PromptCoverageWarning


@dataclass
class Result:
    """A request's motions, their files, the zip of everything, the coverage warnings and a Blender failure."""

    out: MotionOutput
    samples: list[Sample]
    zip: Path
    coverage: list[str]
    blender_error: str | None = None


@contextlib.contextmanager
def coverage_warnings():
    """Yield a list that holds, once the block ends, each distinct PromptCoverageWarning line raised in it; other
    warnings are passed on as usual. (Not thread-safe, as `warnings.catch_warnings`: the page runs one request at a
    time.)"""
    lines: list[str] = []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        yield lines
    for w in caught:
        if issubclass(w.category, PromptCoverageWarning):
            lines.append(str(w.message))
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    lines[:] = list(dict.fromkeys(lines))


def run_request(models: DemoModels, root: Path, kind: str, make: Callable[[], MotionOutput], *,
                video_size: int) -> Result:  # fmt: skip
    """``make()`` the motions in a new ``kind`` request folder under ``root`` and write their files (a failure
    leaves no folder: `request_folder`)."""
    with coverage_warnings() as coverage:
        with request_folder(root, kind) as folder:
            out = make()
            motions = folder / "motions"
            samples, error = write_samples(out, motions, blender=models.glb, video_size=video_size)
            archive = zip_folder(motions, folder / f"motiondiff-{folder.name}.zip")
    return Result(out, samples, archive, coverage, error)
