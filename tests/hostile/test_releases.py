"""Broken, tampered and foreign model files and non-finite numbers through the installed commands: releases with a
flipped bit, a NaN weight, a truncated or mis-shaped weights file, a JSON that breaks the schema or names a path as
its text encoder; garbage, crafted and NaN checkpoints; resumes of another batch size or architecture; NaN settings;
models whose output is NaN. One case of each kind is a subprocess, the rest run in this process (as
tests/hostile/test_boundary.py): exit code 2, one ``error:`` line naming the problem, no traceback, never torch's
weights_only=False advice, no files."""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable
from pathlib import Path

import pytest
import torch
from hostile_cli import REPO, Hostile, assert_refused, files_under
from safetensors.torch import load_file, save_file

from motiondiff.model_files.release_checks import sha256_of

SHIPPED = REPO / "checkpoints" / "models" / "bandai_mini_text_cpu"
SMALL = ("text=walk", "num_samples=1", "export=none", "length=1")
CLIP = "input=test:dataset-1_walk_active_001"
Setup = Callable[[Path], tuple[str, ...]]


def _copy(tmp: Path) -> Path:
    for suffix in (".safetensors", ".json"):
        shutil.copy(SHIPPED.with_suffix(suffix), tmp / f"model{suffix}")
    return tmp / "model"


def _meta(stem: Path) -> dict:
    return json.loads(stem.with_suffix(".json").read_text())


def _rechecksum(stem: Path) -> None:
    stem.with_suffix(".json").write_text(json.dumps({**_meta(stem), "weights_sha256": sha256_of(stem.with_suffix(
        ".safetensors"))}))  # fmt: skip


def release(weights=None, meta=None, raw: Callable[[Path], None] | None = None, checksum: bool = True) -> Setup:
    """A copy of the shipped text release changed by ``weights(state)``, ``meta(dict)`` or ``raw(stem)``; with
    ``checksum`` its JSON records the changed weights' checksum (a careless edit rather than a corruption)."""

    def setup(tmp: Path) -> tuple[str, ...]:
        stem = _copy(tmp)
        if weights is not None:
            state = load_file(str(stem.with_suffix(".safetensors")))
            weights(state)
            save_file(state, str(stem.with_suffix(".safetensors")))
        if raw is not None:
            raw(stem)
        if checksum and stem.with_suffix(".json").is_file():
            _rechecksum(stem)
        if meta is not None:
            data = _meta(stem)
            meta(data)
            stem.with_suffix(".json").write_text(json.dumps(data))
        return (f"checkpoint={stem}.safetensors",)

    return setup


def _set(key: str, value: float):
    def change(state):
        state[key].view(-1)[0] = value

    return change


def _flip_bit(stem: Path) -> None:
    path = stem.with_suffix(".safetensors")
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0x01
    path.write_bytes(bytes(data))


def _json_text(text: bytes) -> Callable[[Path], None]:
    return lambda stem: stem.with_suffix(".json").write_bytes(text)


def _huge(state) -> None:
    """Finite weights whose motion overflows: what check_finite_output is for (NaN weights are refused on load)."""
    state["denoiser.output_proj.bias"][:] = 3e38


def _checkpoint(name: str, build: Callable[[], object], cut: int | None = None) -> Setup:
    def setup(tmp: Path) -> tuple[str, ...]:
        path = tmp / name
        torch.save(build(), path)
        if cut is not None:
            path.write_bytes(path.read_bytes()[:cut])
        return (f"checkpoint={path}",)

    return setup


def _garbage(tmp: Path) -> tuple[str, ...]:
    (tmp / "garbage.ckpt").write_bytes(b"\x00\x01 this is not a checkpoint \xff" * 64)
    return ("checkpoint=garbage.ckpt",)


class _RunsCode:
    def __reduce__(self):
        return (print, ("code ran",))  # os.system would be run the same way


def _lightning(state: dict, **extra) -> dict:
    hparams = _meta(SHIPPED)["hparams"]
    return {"state_dict": state, "hyper_parameters": hparams, "pytorch-lightning_version": "2.5.0", "epoch": 0,
            "global_step": 10, "optimizer_states": [], "loops": {}, **extra}  # fmt: skip


def _nan_state() -> dict:
    state = load_file(str(SHIPPED.with_suffix(".safetensors")))
    state["denoiser.input_proj.weight"][0, 0] = float("nan")
    return _lightning(state)


def _resume(batch_size: int) -> Callable[[Path], tuple[str, ...]]:
    def setup(tmp: Path) -> tuple[str, ...]:
        state = load_file(str(SHIPPED.with_suffix(".safetensors")))
        torch.save(_lightning(state, motiondiff_resume={"batch_size": batch_size}), tmp / "last.ckpt")
        return ("ckpt_path=last.ckpt",)

    return setup


def sample(name: str, setup: Setup | None, *needles: str, args: tuple[str, ...] = (), process=False) -> Hostile:
    return Hostile(name, "sample", SMALL + args, needles, setup, process=process)


def edit(name: str, setup: Setup | None, *needles: str, args: tuple[str, ...] = (), process=False) -> Hostile:
    return Hostile(name, "edit", (CLIP, "num_samples=1", "export=none", "steps=2") + args, needles, setup,
                   process=process)  # fmt: skip


def _without(*keys: str):
    def change(meta: dict) -> None:
        for key in keys:
            target = meta
            *path, last = key.split(".")
            for part in path:
                target = target[part]
            target.pop(last)

    return change


CASES = [
    # the checksum: one flipped bit
    sample(
        "flipped_bit",
        release(raw=_flip_bit, checksum=False),
        "weights_sha256",
        "model.safetensors",
        "restore",
        process=True,
    ),
    # weights that match their checksum but are broken
    sample("nan_weight", release(weights=_set("denoiser.output_proj.weight", float("nan"))), "nan or infinite weights"),
    sample(
        "truncated_weights",
        release(
            raw=lambda s: s.with_suffix(".safetensors").write_bytes(
                SHIPPED.with_suffix(".safetensors").read_bytes()[:4096]
            )
        ),
        "cannot be loaded",
    ),  # fmt: skip
    sample(
        "weights_of_another_shape",
        release(weights=lambda s: s.update({"denoiser.input_proj.weight": torch.zeros(64, 263)})),
        "does not fit",
        "another shape",
    ),  # fmt: skip
    sample("unexpected_tensor", release(weights=lambda s: s.update(extra=torch.zeros(2))), "1 unexpected (first extra"),
    # the JSON: not JSON, not the schema, a path for a text encoder
    sample(
        "json_truncated",
        release(raw=_json_text(b'{"format": "motiondiff-release-1", "hpar'), checksum=False),
        "model.json",
        "not valid json",
    ),  # fmt: skip
    sample("json_nan_token", release(raw=_json_text(b'{"format": NaN}'), checksum=False), "not valid json"),
    sample(
        "json_missing", release(raw=lambda s: s.with_suffix(".json").unlink(), checksum=False), "model.json", "missing"
    ),  # fmt: skip
    sample("json_unknown_key", release(meta=lambda m: m.update(run="rm -rf /")), "unknown key 'run'"),
    sample("json_without_checksum", release(meta=_without("weights_sha256")), "missing key 'weights_sha256'"),
    sample("json_mean_too_short", release(meta=lambda m: m["hparams"].update(mean=[0.0] * 10)), "hparams.mean", "263"),
    sample(
        "text_encoder_with_path",
        release(meta=lambda m: m["hparams"]["text_encoder"].update(path="/tmp/x")),
        "text_encoder.path is not allowed",
    ),  # fmt: skip
    sample(
        "text_encoder_named_by_path",
        release(meta=lambda m: m["hparams"]["text_encoder"].update(name="/home/user/evil_encoder")),
        "not a known text encoder",
    ),  # fmt: skip
    # training checkpoints: garbage, a pickle naming code, truncated, NaN weights
    sample("ckpt_garbage", _garbage, "garbage.ckpt", "cannot be loaded"),
    sample(
        "ckpt_runs_code",
        _checkpoint("crafted.ckpt", lambda: {"state_dict": {}, "x": _RunsCode()}),
        "crafted.ckpt",
        "it would import print",
        "nothing was run",
        process=True,
    ),  # fmt: skip
    sample("ckpt_truncated", _checkpoint("cut.ckpt", _nan_state, cut=20000), "cut.ckpt", "truncated or corrupt"),
    sample("ckpt_nan_weights", _checkpoint("nan.ckpt", _nan_state), "nan.ckpt", "nan or infinite weights"),
    Hostile(
        "guided_ckpt_garbage",
        "sample",
        ("method=guidedmotion", "text=walk", "export=none"),
        ("latent checkpoint", "garbage.ckpt", "cannot be loaded"),
        _garbage,
        process=True,
    ),  # fmt: skip
    # non-finite settings, before any model loads
    sample("guidance_inf", None, "guidance=inf", args=("checkpoint=shipped", "guidance=inf"), process=True),
    sample(
        "eta_nan", None, "sampler.eta=nan", "must be a number in [0, 1]", args=("checkpoint=shipped", "sampler.eta=nan")
    ),
    edit("edit_guidance_nan", None, "guidance=nan", args=("checkpoint=shipped", "guidance=nan")),
    # finite weights whose motion is not: refused before anything is written
    sample(
        "nan_motion",
        release(weights=_huge),
        "the generated motion",
        "nothing was written",
        args=("steps=2",),
        process=True,
    ),
    Hostile(
        "nan_long_motion",
        "sample",
        ("prompts=[walk:1, wave:1]", "num_samples=1", "export=none", "steps=2"),
        ("the long motion", "nothing was written"),
        release(weights=_huge),
    ),  # fmt: skip
    edit("edit_nan_motion", release(weights=_huge), "the edited motion", "nothing was written"),
    edit("edit_nan_weight", release(weights=_set("denoiser.input_proj.bias", float("nan"))), "nan or infinite"),
    Hostile(
        "evaluate_nan_motion",
        "evaluate",
        ("replications=1", "mm_replications=0", "steps=2", "batch_size=16", "action_accuracy=false"),
        ("nothing was written",),
        release(weights=_huge),
    ),  # fmt: skip
    # resuming a run from a checkpoint of another batch size or architecture
    Hostile(
        "resume_other_batch_size",
        "train",
        ("logger=none",),
        ("batch_size=7", "same batch_size"),
        _resume(7),
        process=True,
    ),
    Hostile(
        "resume_other_architecture",
        "train",
        ("logger=none", "model.d_model=64"),
        ("another architecture", "another shape"),
        _resume(64),
    ),  # fmt: skip
]


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_refused_in_one_line_leaving_nothing(results, case):
    proc, tmp = results[case.name]
    assert_refused(proc, *case.needles)
    assert "weights_only" not in proc.stderr, "torch's advice to pass weights_only=False reached the user"
    assert files_under(tmp / "outputs") == [], f"a failed run left {files_under(tmp / 'outputs')}"
