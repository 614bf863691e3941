"""Issue 41's command-line cases that must be refused (and two it lists as fixed before it: NaN guidance and NaN
weights), each as a real process of the installed console script with the arguments the issue names
(docs/reliability.md, "Issue 41's cases and their tests"): exit code 2, exactly one ``error:`` line naming the problem
and the limit or fix, no traceback, and the case's folder (its cwd, outputs and the user's files) exactly as it was
before the run: nothing added, nothing rewritten."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from hostile_cli import Hostile, assert_refused
from issue41_files import bvh_folder, changed, tree
from test_releases import _set, release
from test_user_files import earlier_run

from motiondiff.runtime.settings import MAX_BATCH_SIZE, MAX_REPLICATIONS, MAX_SEGMENT_SECONDS

MODEL = "checkpoint=shipped"
BEFORE: dict[str, dict[str, str]] = {}  # case folder -> its tree once the case's files are made


def _recorded(setup: Callable[[Path], tuple[str, ...]] | None) -> Callable[[Path], tuple[str, ...]]:
    """``setup`` (making the user's files), then the case folder's tree recorded to compare after the run."""

    def made(tmp: Path) -> tuple[str, ...]:
        extra = setup(tmp) if setup else ()
        BEFORE[str(tmp)] = tree(tmp)
        return extra

    return made


def case(name: str, command: str, args: tuple[str, ...], *needles: str, setup=None) -> Hostile:
    return Hostile(name, command, args, needles, _recorded(setup), process=True)


def _int64_joints(tmp: Path) -> tuple[str, ...]:
    np.save(tmp / "ints.npy", np.zeros((40, 22, 3), dtype=np.int64))
    return ("input=ints.npy",)


def _empty_src(tmp: Path) -> tuple[str, ...]:
    (tmp / "src").mkdir()
    return ("bvh", "--src", "src", "--out", "out")


def _users_folder(tmp: Path) -> tuple[str, ...]:
    """A folder of the user's own, with a README.md and report.json a dataset would also write."""
    bvh_folder(tmp / "src")
    (tmp / "mine").mkdir()
    (tmp / "mine" / "README.md").write_text("my notes on this data")
    (tmp / "mine" / "report.json").write_text('{"my": "report"}')
    return ("bvh", "--src", "src", "--out", "mine", "--workers", "1")


def _finished_run(tmp: Path) -> tuple[str, ...]:
    return (f"hydra.run.dir={earlier_run(tmp / 'runs' / 'earlier')}",)


def _max_frames(value: str) -> Hostile:
    def setup(tmp: Path) -> tuple[str, ...]:
        return (*_empty_src(tmp), "--max-frames", value)

    return case(f"prepare_max_frames_{value}", "prepare", (), f"--max-frames {value}: must be a whole number >= 2",
                setup=setup)  # fmt: skip


CASES = [
    # 1. unbounded work from tiny input
    case(
        "sample_walk_1e9",
        "sample",
        (MODEL, "prompts=[walk:1e9, run:1]"),
        "'walk:1e9'",
        f"must be a number in (0, {MAX_SEGMENT_SECONDS:g}]",
    ),
    case(
        "evaluate_replications_1e9",
        "evaluate",
        (MODEL, "replications=1000000000"),
        "replications=1000000000",
        f"in [1, {MAX_REPLICATIONS}]",
    ),
    case(
        "evaluate_batch_size_100000",
        "evaluate",
        (MODEL, "batch_size=100000"),
        "batch_size=100000",
        f"in [1, {MAX_BATCH_SIZE}]",
    ),
    # 2. one line, not a traceback
    case("sample_remove_checkpoint", "sample", ("~checkpoint", "text=walk"), "'~checkpoint' removes a setting"),
    _max_frames("0"),
    _max_frames("1"),
    _max_frames("-5"),
    # 5. silent no-op and silent reinterpretation
    case("sample_no_prompts", "sample", (MODEL, "prompts=[]"), "prompts=[] holds nothing to generate"),
    case(
        "sample_add_misspelt_setting",
        "sample",
        (MODEL, "text=walk", "+lenght=3"),
        "'+lenght=3' adds a setting",
        "did you mean length",
    ),
    case("sample_add_unknown_setting", "sample", (MODEL, "text=walk", "+foo=bar"), "'+foo=bar' adds a setting"),
    # 6. the user's files and the records; words that say what is true
    case(
        "prepare_into_users_folder",
        "prepare",
        (),
        "holds report.json, README.md, which the new dataset would replace",
        "--force",
        setup=_users_folder,
    ),
    case(
        "train_into_finished_run",
        "train",
        ("trainer.max_steps=2",),
        "holds an earlier run",
        "pass ckpt_path=",
        setup=_finished_run,
    ),
    case(
        "sample_checkpoint_dev_zero",
        "sample",
        ("checkpoint=/dev/zero", "text=walk"),
        "/dev/zero",
        "is a pipe or device, not a file",
    ),
    case(
        "edit_int64_joints",
        "edit",
        (MODEL, "kind=parts", "parts=lower_body", "text=walk"),
        "ints.npy: holds int64, expected floating-point",
        setup=_int64_joints,
    ),
]
CASES += [  # earlier failures, fixed before the issue was filed
    case("sample_guidance_nan", "sample", (MODEL, "text=walk", "guidance=nan"), "guidance=nan: must be"),
    case(
        "sample_nan_weights",
        "sample",
        ("text=walk", "length=1", "export=none"),
        "model.safetensors",
        "nan or infinite weights",
        setup=release(weights=_set("denoiser.output_proj.weight", float("nan"))),
    ),
]
UNTRUE = {"sample_checkpoint_dev_zero": "not found", "edit_int64_joints": "NaN"}  # what the line used to say


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_refused_in_one_line_leaving_the_folder_as_it_was(results, case):
    proc, tmp = results[case.name]
    line = assert_refused(proc, *case.needles)
    assert UNTRUE.get(case.name, "\0") not in line, line
    assert changed(BEFORE[str(tmp)], tree(tmp)) == [], "the refused run added to or changed the user's folder"
