"""The coverage check every text generation runs: a prompt far from what the model was trained on gets one warning.

`motiondiff.text.coverage` holds the bank and the arithmetic; this module finds a release's bank, encodes prompts with
the model's own (cached) text features and turns far prompts into warning lines, which `MotionPipeline`, sample.py
and the demo show. A model without a bank (a training checkpoint) cannot be checked, and says so once in the log.
"""

from __future__ import annotations

import logging
import warnings
from pathlib import Path

from motiondiff.lit.conditions import prompt_features
from motiondiff.runtime.errors import UsageError
from motiondiff.text.coverage import CoverageReport, PromptCoverage, coverage_path
from motiondiff.text.prompt_mapping import PromptMapping, check_mode

log = logging.getLogger(__name__)


class PromptCoverageWarning(UserWarning):
    """A prompt is far from every caption the model was trained on (the motion may not be what was asked)."""


def load_coverage(model, model_path: str | Path) -> PromptCoverage | None:
    """The coverage bank beside a text release, or None (not a text model, or no bank: logged once)."""
    if model.condition_kind != "text":
        return None
    path = coverage_path(model_path)
    if not path.is_file():
        log.info("no coverage bank beside %s (%s): prompts far from the training captions cannot be flagged; build "
                 "one with python -m motiondiff.studies.prompt_coverage", model_path, path.name)  # fmt: skip
        return None
    return PromptCoverage.load(path)


def far_prompts(model, coverage: PromptCoverage | None, prompts: list) -> list[CoverageReport]:
    """Reports of the distinct text prompts below the bank's threshold (none without a bank)."""
    texts = [p for p in dict.fromkeys(prompts) if isinstance(p, str)]
    if coverage is None or not texts:
        return []
    features = prompt_features(model, texts).float().numpy()
    return [r for r in coverage.check(texts, features) if r.far]


def warn_far(model, coverage: PromptCoverage | None, prompts: list) -> list[str]:
    """Warn (PromptCoverageWarning) once per far prompt; returns the warning lines."""
    lines = [r.warning() for r in far_prompts(model, coverage, prompts)]
    for line in lines:
        warnings.warn(line, PromptCoverageWarning, stacklevel=3)
    return lines


def load_prompt_mapping(model_path: str | Path, mode: str) -> PromptMapping | None:
    """The prompt mapping of `mode` onto the coverage bank beside a release (None for "none"); a missing bank or an
    unknown mode is one UsageError naming the fix."""
    try:
        check_mode(mode)
    except ValueError as err:
        raise UsageError(str(err)) from None
    if mode == "none":
        return None
    bank = coverage_path(model_path)
    if not bank.is_file():
        raise UsageError(f"prompt_mapping={mode} needs the coverage bank {bank}; build it with "
                         "python -m motiondiff.studies.prompt_coverage, or pass prompt_mapping=none")  # fmt: skip
    return PromptMapping(PromptCoverage.load(bank), mode)
