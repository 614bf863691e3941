"""A release is refused in one UsageError line when its JSON breaks the schema, its weights do not match their
checksum, hold NaN, are truncated or of another shape; checkpoints that are garbage or name code are refused the same
way, never with torch's advice to pass weights_only=False."""

from __future__ import annotations

import json
import pickle
import shutil
from pathlib import Path

import pytest
import torch
from safetensors.torch import load_file, save_file

from motiondiff.model_files.release import load_release
from motiondiff.model_files.release_checks import check_release_meta, read_release_json, sha256_of
from motiondiff.runtime.checked_loading import torch_load
from motiondiff.runtime.errors import UsageError
from motiondiff.runtime.paths import REPO_DIR
from motiondiff.runtime.safe_pickle import RefusedPickle, load_pickle

MODELS = REPO_DIR / "checkpoints" / "models"
SHIPPED = [
    "bandai_mini_text_cpu",
    "bandai_text_cpu",
    "bandai_text_long_12k",
    "bandai_text_long_42k",
    "bandai_text_trans_dec_40k",
    "bandai_action_cpu",
    "bandai_action_trans_dec_14k",
]


@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_releases_carry_their_weights_checksum(name):
    meta = read_release_json(MODELS / f"{name}.json")
    check_release_meta(meta, MODELS / f"{name}.json")
    assert meta["weights_sha256"] == sha256_of(MODELS / f"{name}.safetensors")


@pytest.fixture
def release(tmp_path) -> Path:
    """A copy of the shipped text release: (stem) with .safetensors and .json beside it."""
    for suffix in (".safetensors", ".json"):
        shutil.copy(MODELS / f"bandai_mini_text_cpu{suffix}", tmp_path / f"model{suffix}")
    return tmp_path / "model"


def _meta(stem: Path) -> dict:
    return json.loads(stem.with_suffix(".json").read_text())


def _write_meta(stem: Path, meta: dict) -> None:
    stem.with_suffix(".json").write_text(json.dumps(meta))


def _refused(stem: Path, *needles: str) -> str:
    with pytest.raises(UsageError) as err:
        load_release(stem.with_suffix(".safetensors"))
    line = str(err.value)
    assert "\n" not in line and "weights_only=False" not in line
    for needle in needles:
        assert needle in line, line
    return line


def _rewrite_weights(stem: Path, change) -> None:
    """Change the weights and record their new checksum (a careless edit, not a corruption)."""
    weights = stem.with_suffix(".safetensors")
    state = load_file(str(weights))
    change(state)
    save_file(state, str(weights))
    _write_meta(stem, {**_meta(stem), "weights_sha256": sha256_of(weights)})


def test_one_flipped_bit_is_refused_by_the_checksum(release):
    weights = release.with_suffix(".safetensors")
    data = bytearray(weights.read_bytes())
    data[len(data) // 2] ^= 0x01
    weights.write_bytes(bytes(data))
    _refused(release, "weights_sha256", "model.safetensors", "restore")


def test_a_nan_weight_is_refused(release):
    _rewrite_weights(
        release, lambda s: s[next(k for k in s if k.endswith("weight"))].view(-1).__setitem__(0, torch.nan)
    )
    _refused(release, "NaN or infinite weights")


def test_weights_of_another_shape_are_refused(release):
    def shrink(state):
        key = next(k for k in state if k.endswith("weight") and state[k].ndim == 2)
        state[key] = state[key][:-1].contiguous()

    _rewrite_weights(release, shrink)
    _refused(release, "does not fit", "another shape")


def test_a_truncated_weights_file_is_refused(release):
    weights = release.with_suffix(".safetensors")
    weights.write_bytes(weights.read_bytes()[:1000])
    _write_meta(release, {**_meta(release), "weights_sha256": sha256_of(weights)})
    _refused(release, "cannot be loaded")


@pytest.mark.parametrize(
    ("change", "needles"),
    [
        (lambda m: m.update(extra=1), ("unknown key 'extra'",)),
        (lambda m: m.pop("weights_sha256"), ("missing key 'weights_sha256'",)),
        (lambda m: m.update(weights_sha256="abc"), ("64 lowercase hex",)),
        (lambda m: m.update(format="other"), ("not a motiondiff release",)),
        (lambda m: m["hparams"].update(surprise=True), ("unknown key 'surprise'",)),
        (lambda m: m["hparams"].pop("mean"), ("missing key 'mean'",)),
        (lambda m: m["hparams"].update(mean=m["hparams"]["mean"][:-1]), ("hparams.mean", "263")),
        (lambda m: m["hparams"].update(std=[0.0] * 263), ("hparams.std", "positive")),
        (lambda m: m["hparams"]["model"].update(d_model="128"), ("hparams.model.d_model",)),
        (lambda m: m["hparams"]["model"].update(num_heads=3), ("divisor",)),
        (lambda m: m["hparams"].update(fps=-1), ("hparams.fps",)),
        (lambda m: m["hparams"]["condition"].update(kind="music"), ("condition.kind",)),
        (lambda m: m["hparams"].update(text_encoder={"name": "/tmp/evil", "dim": 384}), ("not a known text encoder",)),
        (lambda m: m["hparams"]["text_encoder"].update(path="/tmp/evil"), ("text_encoder.path is not allowed",)),
        (lambda m: m["hparams"].update(text_encoder=None), ("must name its encoder",)),
    ],
)
def test_schema_breaks_are_refused_before_the_model_is_built(release, change, needles):
    meta = _meta(release)
    change(meta)
    _write_meta(release, meta)
    _refused(release, "model.json", *needles)


@pytest.mark.parametrize("text", ['{"format": ', '{"x": NaN}', "[1, 2]", "\xff\xfe"])
def test_a_config_that_is_not_a_json_object_is_refused(release, text):
    release.with_suffix(".json").write_bytes(text.encode("latin-1"))
    _refused(release, "model.json")


def test_a_missing_half_is_refused(release):
    release.with_suffix(".json").unlink()
    _refused(release, "model.json", "missing")


def test_garbage_and_crafted_checkpoints_are_one_line(tmp_path):
    garbage = tmp_path / "garbage.ckpt"
    garbage.write_bytes(b"\x00\x01 not a checkpoint" * 50)
    with pytest.raises(UsageError, match="garbage.ckpt cannot be loaded") as err:
        torch_load(garbage)
    assert "weights_only" not in str(err.value)
    crafted = tmp_path / "crafted.ckpt"
    torch.save({"state_dict": {}, "run": print}, crafted)
    with pytest.raises(UsageError, match="it would import print .*nothing was run"):
        torch_load(crafted)


def test_the_safe_unpickler_refuses_in_one_line(tmp_path):
    path = tmp_path / "index.pkl"
    path.write_bytes(pickle.dumps({"a": print}))
    with pytest.raises(RefusedPickle, match="builtins.print is not allowed"):
        load_pickle(path)
    path.write_bytes(pickle.dumps({"a": 1})[:-3])
    with pytest.raises(UsageError, match="not a readable pickle"):
        load_pickle(path)


def test_an_oversized_or_deeply_nested_config_is_refused(release):
    release.with_suffix(".json").write_bytes(b" " * (11 << 20))
    _refused(release, "bytes")
    release.with_suffix(".json").write_text("[" * 100_000 + "]" * 100_000)
    _refused(release, "not valid JSON")


def test_a_representation_of_another_width_is_refused(release):
    meta = _meta(release)
    meta["hparams"]["representation"]["name"] = "kit251"
    _write_meta(release, meta)
    _refused(release, "model.json")


def test_a_release_naming_clip_takes_its_folder_from_the_environment(monkeypatch):
    from motiondiff.lit.conditions import CLIP_PATH_ENV, text_encoder_kwargs

    monkeypatch.delenv(CLIP_PATH_ENV, raising=False)
    with pytest.raises(UsageError, match=CLIP_PATH_ENV):
        text_encoder_kwargs({"name": "clip", "dim": 512})
    monkeypatch.setenv(CLIP_PATH_ENV, "/models/clip")
    assert text_encoder_kwargs({"name": "clip", "dim": 512}) == {"name": "clip", "path": "/models/clip"}
    assert text_encoder_kwargs({"name": "minilm", "dim": 384}) == {"name": "minilm"}
