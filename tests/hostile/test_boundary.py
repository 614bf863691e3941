"""The error boundary through the installed commands: bad settings, unreadable input, unusable run folders. One case
of each kind runs as a subprocess, the rest through the same console-script function in the test process
(hostile_cli.run_collected; a module fixture runs every collected case, the tests read the results). Every case:
exit code 2, one ``error:`` line naming the problem, no traceback, and no result files."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest
from hostile_cli import Hostile, assert_refused, files_under

MODEL = "checkpoint=shipped"
SMALL = ("num_samples=1", "export=none", "length=1")
CLIP = "input=test:dataset-1_walk_active_001"


def _file(name: str, data: bytes) -> Callable[[Path], tuple[str, ...]]:
    def setup(tmp: Path) -> tuple[str, ...]:
        (tmp / name).write_bytes(data)
        return ()

    return setup


def _a_file_as_output(tmp: Path) -> tuple[str, ...]:
    (tmp / "taken").write_text("a file where the outputs folder should go")
    return (f"paths.output_dir={tmp / 'taken'}",)


def sample(name, *args, needles, setup=None, model=True, process=False):
    return Hostile(name, "sample", ((MODEL,) if model else ()) + SMALL + args, needles, setup, process=process)


CASES = [
    # settings that do not exist or do not parse
    sample("misspelt_key", "lenght=3", needles=("unknown setting 'lenght'",), process=True),
    sample("unknown_sampler", "text=walk", "sampler=euler", needles=("sampler/euler", "auto, ddim, ddpm, dpmpp")),
    sample("override_syntax", "text=walk", "guidance=[1", needles=("[1",)),
    # numbers: type, finiteness, range, before the model loads
    sample("length_text", "text=walk", "length=abc", needles=("length='abc'", "a number > 0")),
    sample("length_nan", "text=walk", "length=nan", needles=("length=nan", "a number > 0"), process=True),
    sample("length_inf", "text=walk", "length=inf", needles=("length=inf",)),
    sample("length_negative", "text=walk", "length=-1", needles=("length=-1",)),
    sample("frames_zero", "text=walk", "frames=0", needles=("frames=0", "an integer >= 1")),
    sample("frames_fraction", "text=walk", "frames=2.5", needles=("frames=2.5", "an integer")),
    sample("seed_too_big", "text=walk", f"seed={2**70}", needles=("seed=", "in [0, 9223372036854775807]")),
    sample("seed_negative", "text=walk", "seed=-1", needles=("seed=-1",)),
    sample("num_samples_zero", "text=walk", "num_samples=0", needles=("num_samples=0",)),
    sample("num_samples_text", "text=walk", "num_samples=many", needles=("num_samples='many'",)),
    sample("steps_zero", "text=walk", "steps=0", needles=("steps=0",)),
    sample("steps_fraction", "text=walk", "steps=1.5", needles=("steps=1.5",)),
    sample("steps_beyond_chain", "text=walk", "steps=5000", needles=("steps must be between 1",)),
    sample("length_beyond_model", "text=walk", "length=600", needles=("shorter length",)),
    # devices, models and inputs that are not there
    sample("cuda_without_gpu", "text=walk", "device=cuda", needles=("cuda",)),
    sample(
        "missing_checkpoint",
        "text=walk",
        "checkpoint=/nonexistent/model.safetensors",
        needles=("nonexistent",),
        model=False,
        process=True,
    ),  # fmt: skip
    sample("checkpoint_is_a_folder", "text=walk", "checkpoint=.", needles=("checkpoint",), model=False),
    sample("prompts_file_missing", "prompts_file=nowhere.txt", needles=("nowhere.txt", "not found")),
    sample(
        "prompts_file_not_utf8",
        "prompts_file=latin1.txt",
        needles=("utf-8",),
        setup=_file("latin1.txt", "a person walks to the caf\xe9\n".encode("latin-1")),
    ),  # fmt: skip
    sample("prompts_file_empty", "prompts_file=empty.txt", needles=("no prompts",), setup=_file("empty.txt", b"\n\n")),
    sample("empty_text", "text=", needles=("text is empty",)),
    sample("text_and_action", "text=walk", "action=walk", needles=("only one of",)),
    sample("unknown_format", "text=walk", "export=avi", needles=("avi",)),
    sample("mesh_without_body", "text=walk", "export=mp4", "render=mesh", needles=("smpl_model",)),
    Hostile("unknown_action", "sample", (MODEL, *SMALL, "action=fly"), ("unknown action 'fly'",)),
    # run folders that cannot be made
    sample(
        "output_dir_is_a_file", "text=walk", needles=("is a file, not a folder",), setup=_a_file_as_output, process=True
    ),
    sample("run_dir_under_proc", "text=walk", "hydra.run.dir=/proc/motiondiff-run", needles=("cannot make the run",)),
    # edit.py
    Hostile("edit_start_nan", "edit", (MODEL, CLIP, "start=nan", "num_samples=1", "export=none"), ("start=nan",)),
    Hostile(
        "edit_hold_from_above_one",
        "edit",
        (MODEL, CLIP, "hold_from=2", "num_samples=1", "export=none"),
        ("hold_from=2",),
    ),  # fmt: skip
    Hostile(
        "edit_resample_zero", "edit", (MODEL, CLIP, "resample=0", "num_samples=1", "export=none"), ("resample=0",)
    ),  # fmt: skip
    Hostile(
        "edit_missing_input", "edit", (MODEL, "input=nowhere.bvh", "num_samples=1", "export=none"), ("nowhere.bvh",)
    ),  # fmt: skip
    Hostile(
        "edit_garbage_bvh",
        "edit",
        (MODEL, "input=garbage.bvh", "num_samples=1", "export=none"),
        ("garbage.bvh",),
        _file("garbage.bvh", b"\x00\x01 not a bvh at all \xff"),
        process=True,
    ),  # fmt: skip
    Hostile(
        "edit_unknown_parts",
        "edit",
        (MODEL, CLIP, "kind=parts", "parts=tail", "num_samples=1", "export=none"),
        ("tail",),
    ),  # fmt: skip
    # evaluate.py and train.py
    Hostile("evaluate_zero_replications", "evaluate", (MODEL, "replications=0"), ("replications=0",), process=True),
    Hostile("train_batch_zero", "train", ("batch_size=0",), ("batch_size=0",), process=True),
    Hostile("train_heads_do_not_divide", "train", ("model.num_heads=3",), ("model.num_heads=3", "divide")),
    Hostile("train_missing_dataset", "train", ("dataset=bvh", "dataset.root=/nonexistent/bvh"), ("nonexistent",)),
]


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_refused_in_one_line_leaving_nothing(results, case):
    proc, tmp = results[case.name]
    assert_refused(proc, *case.needles)
    left = [f for f in files_under(tmp / "outputs") if not f.startswith("taken")]
    assert left == [], f"a failed run left {left}"
