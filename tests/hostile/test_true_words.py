"""Messages say what is true (issue 41): a device given as a file is "a pipe or device", not "not found"; integer
joints are "int64, expected floating-point", not "NaN or Inf"; `frames=0.5` is about frames; an array given as a
clip id is named as an array; a sweep of a million jobs is refused before Hydra lists them. Through the installed
commands (one ``error:`` line, exit 2, nothing written) and the Python API (one UsageError)."""

from __future__ import annotations

import numpy as np
import pytest
from hostile_cli import assert_refused, files_under, run_in_process

from motiondiff.geometry.skeleton import SMPL22
from motiondiff.pipelines import MotionPipeline
from motiondiff.runtime.errors import UsageError
from motiondiff.runtime.settings import MAX_SWEEP_JOBS

DEVICE = "/dev/zero"


@pytest.fixture(scope="module")
def pipe():
    return MotionPipeline.from_pretrained("text")


@pytest.mark.parametrize(
    "name,args",
    [("sample", ("checkpoint=/dev/zero", "text=walk")), ("sample", ("checkpoint=shipped", "prompts_file=/dev/zero")),
     ("edit", ("checkpoint=shipped", "input=/dev/zero", "kind=parts", "parts=lower_body", "text=walk")),
     ("train", ("ckpt_path=/dev/zero", "trainer.max_steps=1")), ("train", ("init_from=/dev/zero", "trainer.max_steps=1"))],
    ids=["checkpoint", "prompts_file", "edit_input", "ckpt_path", "init_from"],
)  # fmt: skip
def test_a_device_given_as_a_file_is_called_a_device_not_missing(tmp_path, name, args):
    line = assert_refused(run_in_process(tmp_path, name, *args), DEVICE, "is a pipe or device, not a file")
    assert "not found" not in line
    assert files_under(tmp_path / "outputs") == []


def test_integer_joints_are_named_by_their_type(tmp_path, pipe):
    joints = np.zeros((40, 22, 3), dtype=np.int64)
    np.save(tmp_path / "ints.npy", joints)
    proc = run_in_process(tmp_path, "edit", "checkpoint=shipped", f"input={tmp_path / 'ints.npy'}", "kind=parts",
                          "parts=lower_body", "text=walk")  # fmt: skip
    line = assert_refused(proc, "holds int64, expected floating-point joint positions")
    assert "NaN" not in line
    with pytest.raises(UsageError, match="holds int64, expected floating-point"):
        pipe.edit_parts(tmp_path / "ints.npy", "a person waves", steps=2)
    from motiondiff.export.bvh_export import export_bvh  # the exports' one motion check

    with pytest.raises(ValueError, match="joints hold int64, expected floating-point positions"):
        export_bvh(tmp_path / "m.bvh", joints, SMPL22, fps=20)
    assert not (tmp_path / "m.bvh").exists()


def test_api_words_name_what_was_given(pipe):
    with pytest.raises(UsageError, match=r"frames=0\.5: must be a whole number of frames, at least 1"):
        pipe("a person walks", frames=0.5, steps=2)
    with pytest.raises(UsageError, match="got a ndarray: save joints .* with np.save and pass the .npy path"):
        pipe.inbetween(np.zeros((40, 22, 3), dtype=np.float32), "a person waves", steps=2)


def test_a_sweep_of_a_million_jobs_is_refused_before_any_job(tmp_path):
    proc = run_in_process(tmp_path, "sample", "-m", "checkpoint=shipped", "text=walk", "seed=range(0,1000000)")
    assert_refused(proc, f"more than {MAX_SWEEP_JOBS} jobs", f"seed=range(0,1000000): over {MAX_SWEEP_JOBS}")
    assert not (tmp_path / "outputs").exists() and not (tmp_path / "multirun").exists()


def test_a_cuda_device_on_a_machine_without_one_is_one_usage_error():
    import torch

    if torch.cuda.is_available():
        pytest.skip("this machine has a CUDA device")
    with pytest.raises(UsageError, match="device=cuda but this machine has no CUDA device"):
        MotionPipeline.from_pretrained("text", device="cuda")
