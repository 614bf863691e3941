"""Issue 41: the commands and the Python API check a user's settings with one rule table (`runtime.settings`). Every
rule is run through both surfaces with the same bad values: `sample.py` in this process (`run_entry`, as the command
line composes it) and `MotionPipeline`, which must refuse each with the same one message, before any sampling.
The bounds (prompts per call, timed-prompt seconds and count, prompts-file size, replications, batch size) are
refused before any work, with the limit named; output and model-name mistakes are one UsageError."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from fixtures.in_process import files_under, run_entry

from motiondiff.pipelines import MotionPipeline
from motiondiff.runtime.errors import UsageError
from motiondiff.runtime.settings import GENERATION, MAX_PROMPTS, MAX_PROMPTS_FILE_BYTES, MAX_SEGMENT_SECONDS

# (setting, bad value, how the command line writes it)
BAD = [
    ("seed", math.nan, "nan"), ("seed", 2**70, str(2**70)), ("seed", 1.7, "1.7"), ("seed", "abc", "abc"),
    ("seed", -1, "-1"), ("guidance", True, "true"), ("guidance", -1.0, "-1.0"), ("guidance", math.inf, "inf"),
    ("steps", 0, "0"), ("steps", 2.5, "2.5"), ("smooth_sigma", math.inf, "inf"), ("smooth_sigma", "x", "x"),
    ("smooth_sigma", -0.5, "-0.5"), ("eta", "abc", "abc"), ("eta", -0.1, "-0.1"), ("eta", 1.5, "1.5"),
]  # fmt: skip
CLI_KEY = {"eta": "sampler.eta"}


@pytest.fixture(scope="module")
def pipe():
    return MotionPipeline.from_pretrained("text")


def _rule_words(err: BaseException) -> str:
    """What the value must be: the message between the key (each surface's own name for it) and the fix."""
    return str(err).split(": must be ", 1)[1].split("; fix it with", 1)[0]


@pytest.mark.parametrize(("name", "value", "typed"), BAD, ids=[f"{n}={t}" for n, _, t in BAD])
def test_a_bad_setting_gets_the_same_refusal_from_the_command_and_the_api(name, value, typed, pipe, tmp_path):
    key = CLI_KEY.get(name, name)
    with pytest.raises(UsageError, match=rf"^{key}=.*: must be") as cli:
        run_entry("sample", tmp_path, "checkpoint=shipped", "export=none", "text=walk", f"{key}={typed}")
    with pytest.raises(UsageError, match=rf"^{name}=.*: must be") as api:
        pipe("a person walks", **{"seconds": 1, "steps": 2, name: value})
    assert _rule_words(cli.value) == _rule_words(api.value) == GENERATION[name].describe()
    assert not files_under(tmp_path / "outputs")


def test_edit_and_long_check_the_same_rules_before_sampling(pipe):
    for call in (lambda: pipe.inbetween("test:dataset-1_walk_active_001", guidance=math.nan, steps=2),
                 lambda: pipe.long(["a person walks:2", "a person waves:2"], guidance=math.nan, steps=2),
                 lambda: pipe.long(["a person walks:2", "a person waves:2"], seed=1.5, steps=2)):  # fmt: skip
        with pytest.raises(UsageError, match="must be"):
            call()


@pytest.mark.parametrize(
    ("prompts", "message"),
    [(["walk:1e9", "run:1"], rf"seconds after the colon must be a number in \(0, {MAX_SEGMENT_SECONDS:g}\]"),
     (["walk:inf", "run:1"], "seconds after the colon must be"), (["walk:-2", "run:1"], "seconds after the colon"),
     ([f"walk:{MAX_SEGMENT_SECONDS:g}"] * 6, "add up to"), (["walk:1"] * 65, "65 timed prompts in one request")],
)  # fmt: skip
def test_timed_prompts_are_bounded_alike_on_both_surfaces(prompts, message, pipe, tmp_path):
    with pytest.raises(UsageError, match=message):
        pipe.long(prompts, steps=2)
    listed = "[" + ", ".join(prompts) + "]"
    with pytest.raises(UsageError, match=message):
        run_entry("sample", tmp_path, "checkpoint=shipped", "export=none", f"prompts={listed}")
    assert not files_under(tmp_path / "outputs")


def test_prompt_counts_and_prompt_files_are_bounded_before_work(pipe, tmp_path):
    with pytest.raises(UsageError, match=f"{MAX_PROMPTS + 1} prompts in one request; at most {MAX_PROMPTS}"):
        pipe(["a person walks"] * (MAX_PROMPTS + 1), steps=2)
    with pytest.raises(UsageError, match=r"prompts=\[\] holds nothing"):
        run_entry("sample", tmp_path, "checkpoint=shipped", "export=none", "prompts=[]")
    big = tmp_path / "prompts.txt"
    big.write_text("a person walks" * (MAX_PROMPTS_FILE_BYTES // 14 + 1))  # one line, over the size bound
    with pytest.raises(UsageError, match="bytes; at most"):
        run_entry("sample", tmp_path, "checkpoint=shipped", "export=none", f"prompts_file={big}")


@pytest.mark.parametrize(("override", "message"), [("replications=1000000000", "replications=1000000000: must be"),
                                                   ("batch_size=100000", "batch_size=100000: must be"),
                                                   ("split=nonsense", "split='nonsense': must be one of")])  # fmt: skip
def test_evaluate_refuses_unbounded_work_before_loading(override, message, tmp_path):
    with pytest.raises(UsageError, match=message):
        run_entry("evaluate", tmp_path, "checkpoint=shipped", override)


def test_text_that_is_invisible_or_not_text_is_refused(pipe):
    with pytest.raises(UsageError, match="the text is empty"):
        pipe("\u200b\u200b\u200b", steps=2)
    with pytest.raises(UsageError, match="a prompt must be text, got int"):
        pipe(5, steps=2)


def test_outputs_and_model_names_fail_in_one_line(pipe, tmp_path):
    out = pipe("a person walks", seconds=1, steps=2)
    with pytest.raises(UsageError, match="out of range: this output holds 1 motion"):
        out.to_bvh(5)
    with pytest.raises(UsageError, match="smooth_sigma=-1"):
        out.smoothed(-1)
    (tmp_path / "file").write_text("mine")
    with pytest.raises(UsageError, match="is a file, not a folder"):
        out.save(tmp_path / "file")
    assert (tmp_path / "file").read_text() == "mine"
    with pytest.raises(UsageError, match="takes a folder path"):
        out.save(3)
    bad = replace(out, joints=[np.full_like(out.joints[0], np.nan)])
    with pytest.raises(UsageError, match="hold NaN or Inf"):
        bad.save(tmp_path / "nan")
    assert not files_under(tmp_path / "nan")
    with pytest.raises(UsageError, match="no model named"):
        MotionPipeline.from_pretrained("")
    with pytest.raises(UsageError, match="prompt-coverage bank, not a model"):
        MotionPipeline.from_pretrained("bandai_text_cpu.coverage")
    with pytest.raises(UsageError, match="unknown device='meta'"):
        MotionPipeline.from_pretrained("text", device="meta")
