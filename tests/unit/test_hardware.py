"""The CPU presets resolve to a precision this CPU runs fast; sampling's precision=auto picks bf16 only where it
measured faster; device=auto picks the GPU where there is one."""

from __future__ import annotations

import pytest
from hydra import compose, initialize_config_dir

from motiondiff.cli.common import REPO_DIR, register_resolvers
from motiondiff.runtime.hardware import cpu_has_fast_bf16, fast_cpu_precision


def test_cpu_presets_follow_the_cpu():
    register_resolvers()
    expected = "bf16-mixed" if cpu_has_fast_bf16() else "32-true"
    assert fast_cpu_precision() == expected
    with initialize_config_dir(config_dir=str(REPO_DIR / "conf"), version_base="1.3"):
        train = compose("train", overrides=["trainer=cpu"])
        evaluate = compose("evaluate")
    assert train.trainer.precision == expected and evaluate.precision == "auto"
    # what train.py hands to Lightning: resolved, not the interpolation string
    from omegaconf import OmegaConf

    assert OmegaConf.to_container(train.trainer, resolve=True)["precision"] == expected
    with initialize_config_dir(config_dir=str(REPO_DIR / "conf"), version_base="1.3"):
        assert compose("train", overrides=["trainer=cpu", "trainer.precision=32-true"]).trainer.precision == "32-true"


def test_device_auto_is_the_gpu_where_there_is_one(monkeypatch):
    import torch

    from motiondiff.runtime.errors import UsageError
    from motiondiff.runtime.hardware import resolve_device

    monkeypatch.setattr(torch.cuda, "is_available", lambda: False)
    assert resolve_device("auto") == "cpu" and resolve_device(" CPU ") == "cpu"
    with pytest.raises(UsageError, match="no CUDA device"):
        resolve_device("cuda:0")
    monkeypatch.setattr(torch.cuda, "is_available", lambda: True)
    assert resolve_device("auto") == "cuda"


def test_sampling_precision_auto_follows_what_measured_faster(monkeypatch):
    from motiondiff.runtime import hardware
    from motiondiff.runtime.errors import UsageError

    assert hardware.inference_precision("32") == "32-true" and hardware.inference_precision("FP32") == "32-true"
    assert hardware.inference_precision("bf16") == "bf16-mixed" == hardware.inference_precision("bf16-mixed")
    with pytest.raises(UsageError, match=r"precision='half': choose auto .*, bf16 or 32"):
        hardware.inference_precision("half")
    monkeypatch.setattr(hardware, "cpu_has_fast_bf16", lambda: False)
    assert hardware.inference_precision("auto", "cpu", (160, 128, 256)) == "32-true"
    assert hardware.bf16_matmul_is_faster.__wrapped__(160, 128, 256) is False  # not even timed without native bf16
    monkeypatch.setattr(hardware, "cpu_has_fast_bf16", lambda: True)
    for faster, expected in ((True, "bf16-mixed"), (False, "32-true")):
        monkeypatch.setattr(hardware, "bf16_matmul_is_faster", lambda *shape, f=faster: f)
        assert hardware.inference_precision("auto", "cpu", (160, 128, 256)) == expected


def test_the_pipeline_records_the_precision_it_sampled_in():
    from motiondiff.pipelines import MotionPipeline

    out = MotionPipeline.from_pretrained("text", precision="32")("a person walks", seconds=1, steps=2)
    assert out.info["precision"] == "32-true"


def test_bf16_counts_as_fast_only_with_native_bf16_instructions(monkeypatch):
    """oneDNN reports bf16 support on any AVX512 CPU and then emulates it (slower than float32): the kernel's flags
    decide where they can be read; torch's probe alone only where they cannot."""
    import torch

    from motiondiff.runtime import hardware

    flags = dict.fromkeys(hardware.SPEED_FLAGS, False)
    monkeypatch.setattr(torch.ops.mkldnn, "_is_mkldnn_bf16_supported", lambda: True, raising=False)
    for present, expected in (((), True), (("avx2", "avx512f"), False), (("avx512f", "avx512_bf16"), True),
                              (("avx512f", "amx_bf16", "amx_tile"), True)):  # fmt: skip
        monkeypatch.setattr(hardware, "cpu_flags", lambda p=present: {**flags, **dict.fromkeys(p, True)})
        hardware.cpu_has_fast_bf16.cache_clear()
        assert hardware.cpu_has_fast_bf16() is expected, present
        assert hardware.fast_cpu_precision() == ("bf16-mixed" if expected else "32-true")
    hardware.cpu_has_fast_bf16.cache_clear()
