"""The coverage warning (issue 39) with the shipped text model and its bank: "a person jumps forward" (no jump in the
data) warns in one line naming the nearest actions, "a person walks forward" does not; through sample.py and through
MotionPipeline (a PromptCoverageWarning, and the lines in the output's info)."""

from __future__ import annotations

import warnings

import pytest
from cli_helpers import run_cli

from motiondiff.model_files.resolve import SHIPPED_MODELS
from motiondiff.text.coverage import coverage_path

FAST = ["checkpoint=shipped", "num_samples=1", "length=1", "sampler=ddim", "steps=2", "export=none"]

pytestmark = pytest.mark.skipif(not coverage_path(SHIPPED_MODELS["text"]).is_file(),
                                reason="the shipped text model has no coverage bank")  # fmt: skip


def test_sample_warns_for_a_far_prompt_only(tmp_path):
    far = run_cli("sample.py", *FAST, "text=a person jumps forward", env_dir=tmp_path / "far")
    lines = [line for line in far.stderr.splitlines() if line.startswith("warning:")]
    assert len(lines) == 1, far.stderr[-2000:]
    assert "'a person jumps forward' is far from everything" in lines[0] and "nearest known actions" in lines[0]
    near = run_cli("sample.py", *FAST, "text=a person walks forward", env_dir=tmp_path / "near")
    assert "is far from everything" not in near.stderr + near.stdout


def test_the_pipeline_warns_for_a_far_prompt_only():
    from motiondiff.pipelines import MotionPipeline
    from motiondiff.pipelines.coverage import PromptCoverageWarning

    pipe = MotionPipeline.from_pretrained("text")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = pipe(["a person walks forward", "a person jumps forward"], seconds=1, sampler="ddim", steps=2)
    far = [w for w in caught if issubclass(w.category, PromptCoverageWarning)]
    assert len(far) == 1 and "a person jumps forward" in str(far[0].message)
    assert len(out.info["coverage_warnings"]) == 1
