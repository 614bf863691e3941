"""Issue 41's Python API cases as the issue words them, where tests/hostile/test_one_rule_table.py holds the rule
with other values (docs/reliability.md, "Issue 41's cases and their tests"): 10,000 prompts in one call, 2,000
segments in `long()`, a lone ``walk:-2`` or ``walk:inf``, and `out.save()` into a folder whose motion file name is
taken by a folder or whose path runs through a file. Each is one UsageError naming the limit or the fix, before any
sampling, and writes nothing."""

from __future__ import annotations

import pytest
from fixtures.in_process import files_under

from motiondiff.pipelines import MotionPipeline
from motiondiff.runtime.errors import UsageError
from motiondiff.runtime.settings import MAX_PROMPTS, MAX_SEGMENTS


@pytest.fixture(scope="module")
def pipe():
    return MotionPipeline.from_pretrained("text")


def test_ten_thousand_prompts_in_one_call_are_refused_naming_the_limit(pipe):
    with pytest.raises(UsageError, match=f"10000 prompts in one request; at most {MAX_PROMPTS}"):
        pipe(["a person walks"] * 10_000, steps=2)


def test_two_thousand_segments_in_long_are_refused_naming_the_limit(pipe):
    with pytest.raises(UsageError, match=f"2000 timed prompts in one request; at most {MAX_SEGMENTS}"):
        pipe.long(["a person walks:1"] * 2_000, steps=2)


@pytest.mark.parametrize("prompt", ["walk:-2", "walk:inf"])
def test_a_lone_bad_time_is_read_as_a_time_not_as_text(pipe, prompt):
    with pytest.raises(UsageError, match=f"'{prompt}': the seconds after the colon must be"):
        pipe.long([prompt], steps=2)


@pytest.fixture(scope="module")
def out(pipe):
    return pipe("a person walks", seconds=1, steps=2)


def test_saving_where_a_motion_file_name_is_a_folder_is_refused_and_writes_nothing(out, tmp_path):
    taken = tmp_path / "saved" / "a_person_walks_00_joints.npy"
    taken.mkdir(parents=True)
    with pytest.raises(UsageError, match="already holds a_person_walks_00_joints.npy"):
        out.save(tmp_path / "saved")
    assert files_under(tmp_path) == [] and list(taken.iterdir()) == []


def test_saving_into_a_path_through_a_file_is_one_usage_error(out, tmp_path):
    (tmp_path / "notes.txt").write_text("mine")
    with pytest.raises(UsageError, match="cannot create the folder .*notes.txt/walks"):
        out.save(tmp_path / "notes.txt" / "walks")
    assert (tmp_path / "notes.txt").read_text() == "mine" and files_under(tmp_path) == [tmp_path / "notes.txt"]
