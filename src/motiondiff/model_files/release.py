"""Released models: weights as safetensors beside a JSON of the hyper-parameters and provenance.

A Lightning checkpoint is a pickle (optimizer state, callbacks, hyper-parameters); a released model needs none of
that and must never run code when loaded. `save_release` keeps the module's persistent tensors (the EMA weights
when training used EMA, since the checkpoint holds those) and the weights' SHA-256; `load_release` checks the JSON
(`release_checks`), the checksum and that every weight is finite before it rebuilds the module from the JSON.
"""

from __future__ import annotations

import json
from pathlib import Path

import torch
from safetensors.torch import load_file, save_file

from motiondiff.data.representations.spec import bridge_from_spec
from motiondiff.lit.diffusion import MotionDiffusionModule  # lazy: lightning (+4.4 s to import)
from motiondiff.lit.motion_diffusion import MotionDiffusion
from motiondiff.model_files.release_checks import (
    FORMAT,
    LATENT_CLASS,
    MODEL_CLASS,
    RESTORE,
    check_release_files,
    check_release_meta,
    read_release_json,
    release_paths,
    sha256_of,
)
from motiondiff.runtime.atomic import atomic_write
from motiondiff.runtime.checked_loading import check_finite_state, check_same_shapes, reading, torch_load
from motiondiff.runtime.errors import UsageError
from motiondiff.runtime.hardware import cpu_has_fast_bf16, cpu_model
from motiondiff.runtime.provenance import git_state

# provenance["weights_storage"] of a release written with half_matrices: what the loader casts back to float32
HALF_MATRICES = "weight matrices float16, vectors float32"


def save_release(module, path: str | Path, provenance: dict | None = None, half_matrices: bool = False
                 ) -> tuple[Path, Path]:  # fmt: skip
    """Write `<stem>.safetensors` and `<stem>.json` for a MotionDiffusion model or a GuidedMotion latent model with
    its VAEs (atomically, weights first). ``half_matrices``: weight matrices stored as float16 (half the file; loading
    casts them back), vectors (biases, norms, statistics) kept float32: for a release that would pass 20 MiB."""
    weights, config = release_paths(path)
    state = {k: v.detach().cpu().contiguous() for k, v in module.state_dict().items()}
    check_finite_state(state, f"the model to release as {weights}", "release a checkpoint whose weights are finite")
    if half_matrices:
        state = {k: v.half() if v.is_floating_point() and v.dim() >= 2 else v for k, v in state.items()}
        check_finite_state(state, f"the model to release as {weights} (float16 matrices)",
                           "release it without half_matrices: a weight is beyond float16's range")  # fmt: skip
        provenance = {**(provenance or {}), "weights_storage": HALF_MATRICES}
    hparams = json.loads(json.dumps(dict(module.hparams), default=_plain))  # fails loudly on a non-JSON value
    if isinstance(hparams.get("text_encoder"), dict):  # a release names its encoder; a local path stays local
        hparams["text_encoder"].pop("path", None)
    weights.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(weights, lambda tmp: save_file(state, str(tmp)), suffix=".safetensors")
    kind = LATENT_CLASS if type(module).__name__ == LATENT_CLASS else MODEL_CLASS
    meta = {"format": FORMAT, "class": kind, "hparams": hparams, "provenance": provenance or {},
            "weights_sha256": sha256_of(weights)}  # fmt: skip
    text = json.dumps(meta, indent=1, allow_nan=False)
    atomic_write(config, lambda tmp: Path(tmp).write_text(text), suffix=".json")
    return weights, config


def load_release(path: str | Path, device: str = "cpu"):
    """The module of a release, in eval mode (strict: every tensor must match the architecture in the JSON)."""

    weights, config = release_paths(path)
    meta, state = _checked_release(path, MODEL_CLASS)
    with reading(config, "release config", RESTORE):
        module = MotionDiffusion(**meta["hparams"])
        bridge_from_spec(meta["hparams"].get("representation"), meta["hparams"]["feature_dim"])  # what saving reads
    if module.representation.dim != meta["hparams"]["feature_dim"]:
        raise UsageError(f"release config {config}: representation {module.representation.name} has "
                         f"{module.representation.dim} features, not feature_dim={meta['hparams']['feature_dim']}; "
                         f"{RESTORE}")  # fmt: skip
    check_same_shapes(
        state, module.state_dict(), f"release weights {weights}", RESTORE, f"the model {config.name} describes"
    )
    module.load_state_dict(state, strict=True)
    return module.to(device).eval()


def load_latent_release(path: str | Path, device: str = "cpu"):
    """GuidedMotion's latent model (with its three VAEs) from a release, in eval mode; strict like `load_release`."""
    from motiondiff.lit.latent import HierarchicalLatentModule  # lazy: lightning, spacy (+5.1 s to import)

    weights, config = release_paths(path)
    meta, state = _checked_release(path, LATENT_CLASS)
    with reading(config, "release config", RESTORE):
        module = HierarchicalLatentModule(**meta["hparams"])
    check_same_shapes(state, module.state_dict(), f"release weights {weights}", RESTORE,
                      f"the model {config.name} describes")  # fmt: skip
    module.load_state_dict(state, strict=True)
    return module.to(device).eval()


def _checked_release(path: str | Path, expected: str) -> tuple[dict, dict]:
    """(JSON, weights) of a release of class `expected`, every check passed; another class is one clear error."""
    weights, config = release_paths(path)
    meta = check_release_files(path)  # the files, the checksum, finite weights (those numpy reads)
    if meta.get("class") in (MODEL_CLASS, LATENT_CLASS) and meta["class"] != expected:
        use = (
            "GuidedMotion's latent model: use it with sample.py method=guidedmotion or GuidedMotionPipeline"
            if meta["class"] == LATENT_CLASS
            else "a motion model: use it with sample.py or MotionPipeline"
        )
        raise UsageError(f"release {weights} is {use}")
    check_release_meta(meta, config)  # the hyper-parameters too, before anything is built from them
    with reading(weights, "release weights", RESTORE):
        state = load_file(str(weights), device="cpu")
    bf16 = {k: v for k, v in state.items() if v.dtype == torch.bfloat16}  # numpy has no bfloat16
    check_finite_state(bf16, f"release weights {weights}", RESTORE)
    provenance = meta.get("provenance") if isinstance(meta.get("provenance"), dict) else {}
    if provenance.get("weights_storage") == HALF_MATRICES:  # save_release(half_matrices=True); the model is float32
        state = {k: v.float() if v.dtype == torch.float16 and v.dim() >= 2 else v for k, v in state.items()}
    return meta, state


def provenance_of(release: str | Path) -> dict:
    provenance = read_release_json(release_paths(release)[1]).get("provenance", {})
    return provenance if isinstance(provenance, dict) else {}


def _plain(value):
    if isinstance(value, torch.Tensor):
        return value.tolist()
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"hyper-parameter value {value!r} of type {type(value).__name__} cannot be stored as JSON")


def cpu_description() -> str:
    """'<cores>-core <model name> (<fast instruction set>)' of this machine, for a model card."""
    import os

    isa = "native bf16" if cpu_has_fast_bf16() else torch.backends.cpu.get_cpu_capability() + ", no native bf16"
    return f"{os.cpu_count()}-core {cpu_model()} ({isa})"


def release_checkpoint(ckpt: str | Path, out: str | Path, half_matrices: bool = False, **provenance
                       ) -> tuple[Path, Path]:  # fmt: skip
    """Release a training checkpoint (a motion model, with its EMA weights when it trained with EMA, or a
    GuidedMotion latent model with its VAEs) with the training step, the run's
    command line and `provenance` (data, training time, machine, metrics) in the JSON (``half_matrices``: see
    `save_release`)."""
    from motiondiff.lit.latent import HierarchicalLatentModule  # lazy: lightning, spacy (+5.1 s to import)

    state = torch_load(ckpt)
    cls = HierarchicalLatentModule if "vaes" in (state.get("hyper_parameters") or {}) else MotionDiffusionModule
    with reading(ckpt, "checkpoint"):
        module = cls.load_from_checkpoint(ckpt, map_location="cpu", weights_only=True).eval()
    run = Path(ckpt).resolve().parents[1] / "run.json"
    trained = json.loads(run.read_text())["provenance"] if run.is_file() else {}
    argv = trained.get("argv", [])
    info = {"checkpoint": Path(ckpt).name, "train_steps": int(state["global_step"]),
            "command": "python " + " ".join(argv) if argv else None, "trained_at_git": trained.get("git"),
            "released_at_git": git_state(), **provenance}  # fmt: skip
    return save_release(module, out, info, half_matrices)
