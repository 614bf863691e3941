"""A released model (safetensors + JSON) loads back to the same module without unpickling anything."""

from __future__ import annotations

import copy
import json

import pytest
import torch
from hydra import compose, initialize_config_dir

from motiondiff.cli.common import REPO_DIR, register_resolvers
from motiondiff.cli.train import build_module
from motiondiff.data.datamodules import PreparedDataModule, embedded_data_root
from motiondiff.model_files.release import load_release, save_release
from motiondiff.model_files.release_checks import sha256_of
from motiondiff.runtime.errors import UsageError

register_resolvers()


@pytest.fixture(scope="module")
def module():
    dm = PreparedDataModule(embedded_data_root(), batch_size=8, max_frames=40, representation="rp6jr")
    dm.setup("fit")
    overrides = ["model.d_model=32", "model.num_layers=1", "model.num_heads=2", "model.ff_size=64",
                 "condition=action"]  # fmt: skip
    with initialize_config_dir(config_dir=str(REPO_DIR / "conf"), version_base="1.3"):
        cfg = compose("train", overrides=overrides)
    torch.manual_seed(0)
    return build_module(cfg, dm).eval()


def test_release_round_trip_samples_identically(module, tmp_path):
    weights, config = save_release(module, tmp_path / "model", {"steps": 0})
    assert json.loads(config.read_text())["provenance"] == {"steps": 0}
    loaded = load_release(weights)
    assert loaded.representation.name == "rp6jr" and loaded.hparams.action_names == module.hparams.action_names
    for k, v in module.state_dict().items():
        assert torch.equal(v, loaded.state_dict()[k]), k
    args = ([0, 1], torch.tensor([12, 9]))
    a = module.sample(torch.tensor(args[0]), args[1], steps=3, generator=torch.Generator().manual_seed(0))
    b = loaded.sample(torch.tensor(args[0]), args[1], steps=3, generator=torch.Generator().manual_seed(0))
    assert torch.equal(a, b)


def test_half_matrices_store_matrices_in_float16_and_load_as_float32(module, tmp_path):
    from safetensors.torch import load_file

    full, _ = save_release(module, tmp_path / "full")
    half, config = save_release(module, tmp_path / "half", {"steps": 0}, half_matrices=True)
    stored = load_file(str(half))
    assert {v.dtype for k, v in stored.items() if v.dim() >= 2} == {torch.float16}
    assert all(
        v.dtype == module.state_dict()[k].dtype for k, v in stored.items() if v.dim() < 2
    )  # vectors as they were
    assert half.stat().st_size < 0.6 * full.stat().st_size
    assert json.loads(config.read_text())["provenance"]["weights_storage"].startswith("weight matrices float16")
    loaded = load_release(half)
    for k, v in module.state_dict().items():
        got = loaded.state_dict()[k]
        assert got.dtype == v.dtype and torch.equal(got, v.half().to(v.dtype) if v.dim() >= 2 else v), k


def test_missing_or_foreign_files_are_refused(module, tmp_path):
    weights, config = save_release(module, tmp_path / "model")
    meta = json.loads(config.read_text())
    config.write_text(json.dumps({**meta, "format": "something-else"}))
    with pytest.raises(UsageError, match="not a motiondiff release"):
        load_release(tmp_path / "model")
    weights.unlink()
    with pytest.raises(UsageError, match="model.safetensors"):
        load_release(config)


def test_a_release_records_its_weights_checksum(module, tmp_path):
    weights, config = save_release(module, tmp_path / "model")
    assert json.loads(config.read_text())["weights_sha256"] == sha256_of(weights)


def test_a_clip_path_is_not_written_into_a_release(module, tmp_path):
    module.hparams["text_encoder"] = {"name": "clip", "dim": 512, "path": "/home/me/clip"}
    try:
        _, config = save_release(module, tmp_path / "model")
    finally:
        module.hparams["text_encoder"] = None
    assert json.loads(config.read_text())["hparams"]["text_encoder"] == {"name": "clip", "dim": 512}


def test_nan_weights_are_not_released(module, tmp_path):
    broken = copy.deepcopy(module)
    with torch.no_grad():
        next(broken.parameters()).view(-1)[0] = float("nan")
    with pytest.raises(UsageError, match="NaN"):
        save_release(broken, tmp_path / "model")
    assert not (tmp_path / "model.json").exists()
