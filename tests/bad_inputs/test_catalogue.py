"""The catalogue of bad inputs (issue 9): every mistake a user can make with data, commands or files gets one clear
error of a known type whose message names the fix, and leaves no partial output behind.

Each case runs in this process (`fixtures.in_process.run_entry` composes the entry point's config as the command line would),
so the catalogue stays fast. A few inputs are not errors but must still be handled cleanly (non-ASCII text,
an empty captions file, a zero-length clip); they are at the end.
"""

from __future__ import annotations

import logging
import subprocess
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from fixtures.in_process import REPO, files_under, run_entry
from fixtures.tiny_bvh import two_joint_bvh

sys.path.insert(0, str(REPO / "tests" / "e2e"))
from cli_helpers import write_kit_layout  # noqa: E402

from motiondiff.cli.common import UsageError  # noqa: E402
from motiondiff.data.formats.bvh import BVHError, parse_bvh, read_bvh  # noqa: E402
from motiondiff.data.sources.humanml3d import load_official_split  # noqa: E402
from motiondiff.runtime.errors import DatasetNotFoundError, RepresentationError  # noqa: E402

BVH = two_joint_bvh()
CLIP = "input=test:dataset-1_walk_active_001"


@dataclass(frozen=True)
class Case:
    name: str
    run: Callable[[Path], object]  # gets an empty temporary folder
    error: type[BaseException]
    message: str  # a substring of the message that names the problem or the fix


def sample(*overrides):
    return lambda tmp: run_entry("sample", tmp, "checkpoint=shipped", "export=none", *overrides)


def edit(*overrides):
    return lambda tmp: run_entry("edit", tmp, "checkpoint=shipped", "export=none", *overrides)


def train(*overrides):
    return lambda tmp: run_entry("train", tmp, "logger=csv", "trainer.max_steps=1", *overrides)


def kit(change):
    """The official KIT-ML layout with one thing broken, loaded as train.py would."""

    def run(tmp):
        root = write_kit_layout(tmp / "kit")
        change(root)
        return load_official_split(root, "train", "kit")

    return run


def _edit_npy(name, fn):
    def change(root):
        path = root / "new_joint_vecs" / name
        np.save(path, fn(np.load(path)))

    return change


def _nan(a):
    a[3, 5] = np.nan
    return a


def _inf(a):
    a[7, 0] = -np.inf
    return a


def prepare(*args):
    def run(tmp):
        cmd = [sys.executable, "-m", "motiondiff.data.preparing.prepare", *(a.format(tmp=tmp) for a in args)]
        done = subprocess.run(cmd, capture_output=True, text=True, cwd=tmp, timeout=120)
        if done.returncode:
            raise UsageError(done.stderr.strip().splitlines()[-1] if done.stderr.strip() else f"exit {done.returncode}")
        return done

    return run


def write(name, data: bytes | str):
    def run(tmp):
        path = tmp / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data if isinstance(data, bytes) else data.encode())
        return path

    return run


def _prompts_file(content):
    def run(tmp):
        path = tmp / "prompts.txt"
        path.write_text(content)
        return run_entry("sample", tmp, "checkpoint=shipped", "export=none", f"prompts_file={path}")

    return run


def _bvh_file(data: bytes):
    def run(tmp):
        path = tmp / "clip.bvh"
        path.write_bytes(data)
        return read_bvh(path)

    return run


CASES = [
    # data: BVH files
    Case("bvh_not_a_bvh", lambda tmp: parse_bvh("hello world"), BVHError, "a BVH file starts with 'HIERARCHY'"),
    Case("bvh_binary_garbage", _bvh_file(b"\x00\xff\xfe\x10 garbage"), BVHError, "check that this is a BVH file"),
    Case("bvh_truncated_motion", lambda tmp: parse_bvh(BVH[: BVH.rindex("0 0 0 0 0 0 0 0 0") + 5]), BVHError, "truncated"),
    Case("bvh_truncated_hierarchy", lambda tmp: parse_bvh(BVH[: BVH.index("JOINT Spine")]), BVHError, "the file is cut"),
    Case("bvh_nan_in_motion", lambda tmp: parse_bvh(BVH.replace("0 0 0 0 0 0 0 0 0", "0 0 nan 0 0 0 0 0 0", 1)), BVHError, "NaN or Inf"),
    # data: official HumanML3D/KIT-ML layout
    Case("features_nan", kit(_edit_npy("00001.npy", _nan)), ValueError, "NaN/Inf values (first in frame 3)"),
    Case("features_inf", kit(_edit_npy("00002.npy", _inf)), ValueError, "NaN/Inf values (first in frame 7)"),
    Case("features_wrong_width", kit(lambda r: np.save(r / "new_joint_vecs" / "00001.npy", np.zeros((60, 263), np.float32))),
         ValueError, "(that is the width of dataset='humanml3d')"),
    Case("features_not_npy", kit(lambda r: (r / "new_joint_vecs" / "00001.npy").write_bytes(b"not numpy")), ValueError, "not a readable .npy array"),
    Case("mean_missing", kit(lambda r: (r / "Mean.npy").unlink()), DatasetNotFoundError, "Mean.npy not found"),
    Case("std_wrong_width", kit(lambda r: np.save(r / "Std.npy", np.ones(250, np.float32))), ValueError, "statistics have shape (250,)"),
    Case("split_file_missing", kit(lambda r: (r / "train.txt").unlink()), DatasetNotFoundError, "train.txt not found"),
    Case("no_clip_of_the_split_exists", kit(lambda r: (r / "train.txt").write_text("99998\n99999\n")), DatasetNotFoundError, "has a .npy"),
    Case("dataset_root_missing", lambda tmp: load_official_split(tmp / "nowhere", "train", "kit"), DatasetNotFoundError, "How to get it"),
    # data: the prepare command
    Case("prepare_unreadable_zip", lambda tmp: (write("broken.zip", b"PK\x03\x04 truncated")(tmp), prepare("bvh", "--src", "{tmp}/broken.zip", "--out", "{tmp}/out")(tmp)),
         UsageError, "cannot read it as a zip"),
    Case("prepare_source_missing", prepare("bvh", "--src", "{tmp}/nothing_here", "--out", "{tmp}/out"), UsageError, "no such file or folder"),
    Case("prepare_output_is_a_file", lambda tmp: (write("taken", "x")(tmp), write("src/a.bvh", BVH)(tmp), prepare("bvh", "--src", "{tmp}/src", "--out", "{tmp}/taken")(tmp)),
         UsageError, "is a file, not a folder"),
    # commands: sample.py
    Case("text_empty", sample("text=''"), UsageError, "the text is empty"),
    Case("text_whitespace", sample("text='   '"), UsageError, "the text is empty"),
    Case("text_10000_characters", sample("text=" + "a" * 10000), UsageError, "keep it under"),
    Case("device_cuda_without_cuda", sample("text=walk", "device=cuda"), UsageError, "no CUDA device"),
    Case("device_unknown", sample("text=walk", "device=quantum"), UsageError, "unknown device='quantum'"),
    Case("length_zero", sample("text=walk", "length=0"), UsageError, "length=0: must be a number > 0"),
    Case("length_negative", sample("text=walk", "length=-3"), UsageError, "length=-3: must be a number > 0"),
    Case("length_beyond_maximum", sample("text=walk", "length=600"), UsageError, "ask for a shorter length"),
    Case("num_samples_zero", sample("text=walk", "num_samples=0"), UsageError, "num_samples=0: must be an integer >= 1"),
    Case("guidance_negative", sample("text=walk", "guidance=-1"), UsageError, "guidance=-1: must be a number >= 0"),
    Case("steps_beyond_the_diffusion", sample("text=walk", "steps=5000"), UsageError, "steps must be between 1 and the model's 1000"),
    Case("action_for_a_text_model", lambda tmp: run_entry("sample", tmp, f"checkpoint={REPO}/checkpoints/models/bandai_text_cpu.safetensors",
                                                          "export=none", "action=walk"), UsageError, "this model is text-conditioned"),
    Case("text_for_an_action_model", lambda tmp: run_entry("sample", tmp, f"checkpoint={REPO}/checkpoints/models/bandai_action_cpu.safetensors",
                                                           "export=none", "text=walk"), UsageError, "conditioned on actions: pass action="),
    Case("checkpoint_missing", lambda tmp: run_entry("sample", tmp, "checkpoint=/no/such/model.ckpt", "text=walk"), UsageError, "not found"),
    Case("prompts_file_missing", lambda tmp: run_entry("sample", tmp, "checkpoint=shipped", f"prompts_file={tmp}/none.txt"), UsageError, "not found"),
    Case("prompts_file_empty", _prompts_file("\n  \n"), UsageError, "has no prompts"),
    Case("timed_prompt_zero_seconds", sample("prompts=[a person walks:0, a person waves:2]"), UsageError, "seconds after the colon must be a number in"),
    Case("export_unknown_format", sample("text=walk", "export=[usd]"), UsageError, "choose from mp4, gif, bvh, html"),
    Case("cleanup_unknown", sample("text=walk", "cleanup=hands"), UsageError, "unknown clean-up 'hands'; choose cleanup=bones"),
    # commands: edit.py and evaluate.py
    Case("edit_input_missing", edit("input=/no/such/clip.bvh", "kind=inbetween"), UsageError, "not found"),
    Case("edit_unknown_clip_id", edit("input=test:no_such_clip", "kind=inbetween"), UsageError, "clip ids look like"),
    Case("edit_keeps_everything", edit(CLIP, "kind=inbetween", "prefix=0.6", "suffix=0.6"), UsageError, "leaving nothing to generate"),
    Case("edit_unknown_body_part", edit(CLIP, "kind=parts", "parts=[tail]"), UsageError, "unknown body part 'tail'"),
    Case("edit_cleanup_unknown", edit(CLIP, "kind=inbetween", "cleanup=toes"), UsageError, "unknown clean-up 'toes'"),
    Case("edit_cleanup_bones", edit(CLIP, "kind=inbetween", "cleanup=bones"), UsageError, "cleanup=bones refits every frame and would move the part the edit kept"),
    Case("checkpoint_of_another_dataset", lambda tmp: run_entry("evaluate", tmp, "checkpoint=shipped", "dataset=kit", "wandb=false"),
         UsageError, "the checkpoint was trained on 'bandai'; pass dataset=bandai"),
    Case("evaluate_smoothing_negative", lambda tmp: run_entry("evaluate", tmp, "checkpoint=shipped", "smooth_sigma=-1", "wandb=false"),
         UsageError, "smooth_sigma is a Gaussian's width in frames"),
    Case("clip_x0_unknown_rule", sample("text=walk", "clip_x0=imagen"), UsageError, "choose none, static or dynamic"),
    Case("timestep_spacing_unknown", sample("text=walk", "timestep_spacing=trailing"), UsageError,
         "unknown timestep spacing 'trailing'; choose one of uniform, leading, logsnr"),
    Case("timestep_spacing_leading_on_steps_that_do_not_divide", sample("text=walk", "sampler=ddim", "steps=7",
         "timestep_spacing=leading"), UsageError, "timestep_spacing=leading: leading timestep spacing takes a number of steps that divides"),
    Case("clip_x0_on_a_model_without_range", lambda tmp: run_entry("sample", tmp, f"checkpoint={REPO}/checkpoints/models/bandai_text_cpu.safetensors",
                                                                   "export=none", "text=walk", "clip_x0=static"), UsageError, "has no x0 range"),
    # commands: train.py
    Case("batch_size_zero", train("batch_size=0"), UsageError, "batch_size=0: must be an integer >= 1"),
    Case("batch_size_not_a_number", train("batch_size=abc"), UsageError, "batch_size='abc'"),
    Case("learning_rate_zero", train("optim.lr=0"), UsageError, "optim.lr=0: must be a number > 0"),
    Case("dropout_above_one", train("model.dropout=1.5"), UsageError, "model.dropout=1.5"),
    Case("heads_do_not_divide_width", train("model.num_heads=3"), UsageError, "must divide model.d_model=128"),
    Case("max_frames_negative", train("dataset.datamodule.max_frames=-5"), UsageError, "dataset.datamodule.max_frames=-5"),
    Case("unknown_representation", train("representation=quaternions"), UsageError, "must be one of hml263"),
    Case("representation_of_another_skeleton", train("representation=kit251"), RepresentationError, "use 'hml263'"),
    Case("resume_checkpoint_missing", train("ckpt_path=/no/such/last.ckpt"), UsageError, "pass the last.ckpt of the run"),
    Case("sample_video_count_zero", train("condition=none", "callbacks.evaluation.videos.count=0"), UsageError, "videos.count=0: must be an integer from 1 to 8"),
    Case("sample_video_of_an_unknown_action", train("condition=action", "callbacks.evaluation.videos.actions=[fly]"), UsageError, "no action 'fly'; its actions are"),
    # files
    Case("output_folder_inside_a_file", lambda tmp: (write("outputs", "x")(tmp), write("src/a.bvh", BVH)(tmp), prepare("bvh", "--src", "{tmp}/src", "--out", "{tmp}/outputs/new")(tmp)),
         UsageError, "outputs"),
]  # fmt: skip


def test_the_catalogue_has_at_least_30_cases():
    assert len(CASES) >= 30 and len({c.name for c in CASES}) == len(CASES)


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_bad_input_is_one_clear_error_and_leaves_nothing(case, tmp_path):
    with pytest.raises(case.error) as err:
        case.run(tmp_path)
    message = str(err.value)
    assert case.message in message, message
    assert "Traceback" not in message and message.count("\n") < 12  # one error, not a dump
    for folder in ("run", "outputs/train", "outputs/sample", "out"):  # no partial outputs
        assert files_under(tmp_path / folder) == [], f"{case.name} left {files_under(tmp_path / folder)}"


def test_non_ascii_text_is_accepted_and_files_are_named_in_ascii(tmp_path):
    run_entry("sample", tmp_path, "checkpoint=shipped", "export=none", "text='une personne marche vers l’avant 🚶'",
              "num_samples=1", "steps=2")  # fmt: skip
    names = [p.name for p in files_under(tmp_path / "run")]
    assert "une_personne_marche_vers_l_avant_00_joints.npy" in names and all(n.isascii() for n in names)


def test_an_empty_captions_file_skips_its_clip_with_a_named_warning(tmp_path, caplog):
    root = write_kit_layout(tmp_path / "kit")
    (root / "texts" / "00001.txt").write_text("")
    with caplog.at_level(logging.WARNING):
        records, _, _ = load_official_split(root, "train", "kit")
    assert "00001" not in {r.meta["clip_id"] for r in records} and len(records) == 7
    assert "empty file" in caplog.text and "00001" in caplog.text


def test_a_zero_length_clip_is_left_out_by_the_length_rules(tmp_path):
    root = write_kit_layout(tmp_path / "kit")
    np.save(root / "new_joint_vecs" / "00001.npy", np.zeros((0, 251), np.float32))
    records, _, _ = load_official_split(root, "train", "kit")
    assert "00001" not in {r.meta["clip_id"] for r in records} and len(records) == 7
