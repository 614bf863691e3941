"""The demo's own inputs and example prompts, without a model: the sampling settings, the timeline box and the
in-between shares read as the API takes them (mistakes are one UsageError with the fix); example prompts come from
the model's training vocabulary (its coverage bank's actions through the caption phrases, an action model's names),
with a fallback; the request collects prompt-coverage warnings and passes other warnings on."""

from __future__ import annotations

import warnings
from types import SimpleNamespace

import pytest

from motiondiff.data.preparing.captions import CONTENT_PHRASES
from motiondiff.demo.examples import COMPOUND, FALLBACK, example_prompts, example_timelines
from motiondiff.demo.inputs import Sampling, parse_weights, share, timeline_items, whole
from motiondiff.demo.requests import coverage_warnings
from motiondiff.pipelines.coverage import PromptCoverageWarning
from motiondiff.runtime.errors import UsageError


@pytest.mark.parametrize(
    "text, expect", [(None, None), ("  ", None), ("2, 0.5", [2.0, 0.5]), ("1;0", [1.0, 0.0]), ("3", [3.0])]
)
def test_local_action_weights(text, expect):
    assert parse_weights(text) == expect


def test_bad_weights_are_a_usage_error():
    with pytest.raises(UsageError, match="numbers separated by commas"):
        parse_weights("2, lots")


def test_whole_numbers_from_the_page():
    assert whole(3.0, "seed", 0, 10) == 3
    for bad in (1.5, -1, "x", None):
        with pytest.raises(UsageError, match="seed must be a whole number"):
            whole(bad, "seed", 0, 10)


def test_sampling_settings_are_read_from_the_page_once():
    sampling = Sampling.from_page(seed=3.0, steps="", guidance=2.5, num_samples=2.0)  # as Gradio sends them
    assert sampling == Sampling(seed=3, steps=None, guidance=2.5, num_samples=2) and isinstance(sampling.seed, int)
    assert sampling.ddim() == {"num_samples": 2, "seed": 3, "sampler": "ddim", "steps": None, "guidance": 2.5}
    assert Sampling.from_page(steps=7.0).steps == 7


@pytest.mark.parametrize(
    "field, value, message",
    [("num_samples", 5, "number of samples must be a whole number in 1..4"), ("num_samples", 1.5, "whole number"),
     ("seed", -1, "seed must be"), ("steps", 0, "steps must be"), ("steps", "x", "steps must be a whole number")],
)  # fmt: skip
def test_bad_sampling_settings_are_a_usage_error(field, value, message):
    with pytest.raises(UsageError, match=message):
        Sampling.from_page(**{"seed": 0, "steps": 5, "num_samples": 1, field: value})


def test_timeline_lines_become_timed_prompts():
    box = "a person walks : 2\n\n  a person waves the right hand:1.5s \na person bows\n"
    assert timeline_items(box, 3.0) == ["a person walks:2", "a person waves the right hand:1.5", "a person bows:3"]
    with pytest.raises(UsageError, match="the timeline is empty"):
        timeline_items(" \n ", 2.0)
    with pytest.raises(UsageError, match="seconds after the colon must be a number"):
        timeline_items("a person walks : 0", 2.0)


def test_inbetween_shares_are_percent_of_the_motion():
    assert share(25, "kept start") == 0.25 and share(0, "kept end") == 0.0
    with pytest.raises(UsageError, match="kept end must be a percentage from 0 to 50"):
        share(60, "kept end")


def test_examples_come_from_the_models_training_actions():
    text_model = SimpleNamespace(condition_kind="text", coverage=SimpleNamespace(action_names=["bow", "wave-right-hand",
                                                                                               "new-move"]))  # fmt: skip
    prompts = example_prompts(text_model)
    assert prompts == [f"a person {CONTENT_PHRASES['bow']}", f"a person {CONTENT_PHRASES['wave-right-hand']}",
                       "a person new move"]  # fmt: skip
    assert example_prompts(SimpleNamespace(condition_kind="action", actions=["walk", "kick"])) == ["walk", "kick"]
    assert example_prompts(SimpleNamespace(condition_kind="text", coverage=None)) == list(FALLBACK)
    assert example_prompts(object()) == list(FALLBACK)  # a pipeline with no vocabulary of its own
    assert example_prompts(SimpleNamespace(latent=None)) == list(COMPOUND)  # GuidedMotion: several actions a caption
    assert all(", then " in p for p in COMPOUND)


def test_example_timelines_chain_distinct_examples():
    examples = [f"p{k}" for k in range(9)]
    timelines = example_timelines(examples)
    assert len(timelines) == 3 and len(set(timelines)) == 3
    for t in timelines:
        lines = t.splitlines()
        assert len(lines) == 3 and len(set(lines)) == 3
        assert timeline_items(t, 1.0) == [line.replace(" : ", ":") for line in lines]
    assert example_timelines([]) == []


def test_a_request_collects_coverage_warnings_and_passes_others_on():
    with warnings.catch_warnings(record=True) as outside:
        warnings.simplefilter("always")
        with coverage_warnings() as lines:
            warnings.warn("'fly' is far from everything", PromptCoverageWarning, stacklevel=1)
            warnings.warn("'fly' is far from everything", PromptCoverageWarning, stacklevel=1)
            warnings.warn("something else", UserWarning, stacklevel=1)
    assert lines == ["'fly' is far from everything"]
    assert [str(w.message) for w in outside] == ["something else"]
