"""A checkpoint from a stranger must not run code. Every loader is fed a crafted pickle whose unpickling would create
a marker file (the way `os.system` would run a command): each refuses it and the marker never appears. A scan of
the sources keeps every torch.load / load_from_checkpoint / Lightning resume on weights_only=True."""

from __future__ import annotations

import pickle
import re
from pathlib import Path

import pytest
import torch

SRC = Path(__file__).resolve().parents[2] / "src" / "motiondiff"


class _Payload:
    """Unpickling this calls open(marker, "w"): any code would run the same way."""

    def __init__(self, marker: Path):
        self.marker = str(marker)

    def __reduce__(self):
        return (open, (self.marker, "w"))


@pytest.fixture
def crafted(tmp_path) -> tuple[Path, Path]:
    marker = tmp_path / "code_ran"
    path = tmp_path / "stranger.ckpt"
    torch.save({"state_dict": {"w": torch.zeros(1)}, "hyper_parameters": {}, "payload": _Payload(marker)}, path)
    return path, marker


def _refused(load, path: Path, marker: Path, one_line: bool = True) -> None:
    """Refused without running code; through the project's loaders as one UsageError naming the file (never torch's
    advice to pass weights_only=False), through torch directly as its own UnpicklingError."""
    from motiondiff.runtime.errors import UsageError

    with pytest.raises(UsageError if one_line else pickle.UnpicklingError) as err:
        load(path)
    if one_line:
        assert "nothing was run" in str(err.value) and str(path) in str(err.value)
        assert "weights_only=False" not in str(err.value)
    assert not marker.exists(), "the crafted pickle ran code"


def test_a_plain_unpickler_would_run_the_payload(crafted):
    path, marker = crafted
    torch.load(path, weights_only=False)  # what an unsafe loader does
    assert marker.exists()


def test_sampling_loader_refuses_a_crafted_checkpoint(crafted):
    from motiondiff.model_files.loading import load_model as load_module

    _refused(load_module, *crafted)


def test_fine_tune_loader_refuses_a_crafted_checkpoint(crafted):
    from motiondiff.cli.train import init_weights

    _refused(lambda p: init_weights(None, str(p)), *crafted)


def test_vae_and_latent_loaders_refuse_a_crafted_checkpoint(crafted):
    from motiondiff.cli.train_latent import load_vaes
    from motiondiff.lit.latent import HierarchicalLatentModule

    path, marker = crafted
    _refused(lambda p: load_vaes({"motion": p, "action": p, "specific": p}), path, marker)
    _refused(
        lambda p: HierarchicalLatentModule.load_from_checkpoint(p, map_location="cpu", weights_only=True),
        path,
        marker,
        one_line=False,
    )


def test_official_evaluator_loader_refuses_a_crafted_checkpoint(crafted):
    from motiondiff.model_files.evaluators import load_official_action_classifier

    _refused(load_official_action_classifier, *crafted)


def test_a_pickle_named_safetensors_is_not_unpickled(crafted, tmp_path):
    from safetensors import SafetensorError

    from motiondiff.model_files.release import load_release

    path, marker = crafted
    fake = tmp_path / "model.safetensors"
    fake.write_bytes(path.read_bytes())
    (tmp_path / "model.json").write_text("{}")
    with pytest.raises((SafetensorError, ValueError, KeyError)):
        load_release(fake)
    assert not marker.exists()


def test_every_loader_in_the_sources_is_restricted():
    loads = re.compile(r"(torch\.load|load_from_checkpoint)\(")
    unsafe = []
    for path in SRC.rglob("*.py"):
        text = path.read_text()
        for m in loads.finditer(text):
            call = text[m.start() : text.find("\n", m.start())]
            if "weights_only=True" not in call and '"""' not in call and not call.strip().startswith("#"):
                unsafe.append(f"{path.relative_to(SRC)}: {call.strip()}")
        for m in re.finditer(r"\.fit\(", text):
            call = text[m.start() : text.find("\n", m.start())]
            if "ckpt_path" in call and "weights_only=True" not in call:
                unsafe.append(f"{path.relative_to(SRC)}: {call.strip()} (a resume)")
        if "pickle.load" in text and path.name != "safe_pickle.py":
            unsafe.append(f"{path.relative_to(SRC)}: pickle.load outside safe_pickle")
    assert not unsafe, "\n".join(unsafe)
