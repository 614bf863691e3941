"""The CPU presets resolve to a precision this CPU runs fast; device=auto picks the GPU where there is one."""

from __future__ import annotations

import pytest
from hydra import compose, initialize_config_dir

from motiondiff.cli.common import REPO_DIR, register_resolvers
from motiondiff.hardware import cpu_has_fast_bf16, fast_cpu_precision


def test_cpu_presets_follow_the_cpu():
    register_resolvers()
    expected = "bf16-mixed" if cpu_has_fast_bf16() else "32-true"
    assert fast_cpu_precision() == expected
    with initialize_config_dir(config_dir=str(REPO_DIR / "conf"), version_base="1.3"):
        train = compose("train", overrides=["trainer=cpu"])
        evaluate = compose("evaluate")
    assert train.trainer.precision == expected and evaluate.precision == expected
    # what train.py hands to Lightning: resolved, not the interpolation string
    from omegaconf import OmegaConf

    assert OmegaConf.to_container(train.trainer, resolve=True)["precision"] == expected
    with initialize_config_dir(config_dir=str(REPO_DIR / "conf"), version_base="1.3"):
        assert compose("train", overrides=["trainer=cpu", "trainer.precision=32-true"]).trainer.precision == "32-true"


def test_device_auto_is_the_gpu_where_there_is_one(monkeypatch):
    import torch

    from motiondiff.errors import UsageError
    from motiondiff.hardware import resolve_device

    monkeypatch.setattr(torch.cuda, "is_available", lambda: False)
    assert resolve_device("auto") == "cpu" and resolve_device(" CPU ") == "cpu"
    with pytest.raises(UsageError, match="no CUDA device"):
        resolve_device("cuda:0")
    monkeypatch.setattr(torch.cuda, "is_available", lambda: True)
    assert resolve_device("auto") == "cuda"
