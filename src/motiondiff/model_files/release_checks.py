"""What a release's JSON must hold before a model is built from it, and its weights file's checksum.

A release is read from a file a user downloaded or edited: its JSON is checked against a schema (keys, types, shapes
of the normalisation and action lists) so a bad file is one clear line, never a traceback from deep inside a
constructor. Its text encoder is a known encoder's name, never a path the file could point anywhere.
"""

from __future__ import annotations

import hashlib
import inspect
import json
import math
import re
from pathlib import Path

from motiondiff.model_files.resolve import RELEASE_SUFFIXES
from motiondiff.models.hierarchical import LEVELS
from motiondiff.runtime.checked_loading import reading
from motiondiff.runtime.errors import UsageError
from motiondiff.text.encoders import TEXT_ENCODERS

FORMAT = "motiondiff-release-1"
MODEL_CLASS = "MotionDiffusionModule"  # the class a release names (loaded as lit.motion_diffusion.MotionDiffusion)
LATENT_CLASS = "HierarchicalLatentModule"  # GuidedMotion's latent model with its three VAEs (lit.latent)
MODEL_CLASSES = (MODEL_CLASS, LATENT_CLASS)
TOP_KEYS = {"format", "class", "hparams", "provenance", "weights_sha256"}
CONDITION_KINDS = ("text", "action", "none")
ENCODER_KEYS = {"name", "dim", "max_length"}  # never "path": a release names its encoder, the user's config finds it
MAX_CONFIG_BYTES = 10 << 20  # a release JSON is kilobytes (hyper-parameters, statistics, provenance)
RESTORE = "restore the release (`git checkout -- checkpoints` for a shipped one) or release the checkpoint again"


def release_paths(path: str | Path) -> tuple[Path, Path]:
    """(weights, config) of a release named by either file or their common stem."""
    stem = Path(path)
    if stem.suffix in RELEASE_SUFFIXES:
        stem = stem.with_suffix("")
    return stem.with_suffix(".safetensors"), stem.with_suffix(".json")


def check_release_files(path: str | Path) -> dict:
    """The checks of a release that need no model and no torch (its files, the JSON's top level, the checksum,
    finite weights): a command runs them before its heavy imports, so a broken release is refused in a second.
    Returns the JSON, which loading (``release.load_release``) goes on to check in full, with the shapes."""
    weights, config = release_paths(path)
    for f in (weights, config):
        if not f.is_file():
            raise UsageError(f"release file {f} is missing: a release is {weights.name} + {config.name} side by side")
    meta = read_release_json(config)
    check_release_meta(meta, config, hparams=False)
    check_weights_checksum(weights, config, meta["weights_sha256"])
    from safetensors import safe_open  # numpy views: no torch

    with reading(weights, "release weights", RESTORE):
        with safe_open(str(weights), framework="numpy") as f:
            bad = [k for k in f.keys() if _numpy_float(f, k) and not _finite(f.get_tensor(k))]
    if bad:
        raise UsageError(f"release weights {weights} holds NaN or infinite weights ({len(bad)} tensor(s), first "
                         f"{bad[0]!r}): the weights are corrupt or diverged; {RESTORE}")  # fmt: skip
    return meta


def _numpy_float(f, key: str) -> bool:
    """Whether numpy can read this tensor as floats (bfloat16 it cannot: loading checks those)."""
    return f.get_slice(key).get_dtype() in ("F16", "F32", "F64")


def _finite(array) -> bool:
    import numpy as np

    return bool(np.isfinite(array).all())


def sha256_of(path: str | Path) -> str:
    """Hex SHA-256 of a file, read in 1 MiB blocks."""
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def read_release_json(config: Path) -> dict:
    """The parsed JSON of a release, or one UsageError for a file that is not JSON (or far too big to be one)."""
    size = config.stat().st_size
    if size > MAX_CONFIG_BYTES:
        raise UsageError(f"release config {config} has {size} bytes, more than a release's JSON ever needs "
                         f"({MAX_CONFIG_BYTES >> 20} MiB); {RESTORE}")  # fmt: skip
    try:
        meta = json.loads(config.read_bytes().decode("utf-8"), parse_constant=_no_constant)
    except (UnicodeDecodeError, json.JSONDecodeError, ValueError, RecursionError) as err:
        raise UsageError(f"release config {config} is not valid JSON ({_short(err)}); {RESTORE}") from None
    if not isinstance(meta, dict):
        raise UsageError(f"release config {config} holds {type(meta).__name__}, not a JSON object; {RESTORE}")
    return meta


def _no_constant(name: str):
    raise ValueError(f"{name} is not a number JSON allows")


def check_weights_checksum(weights: Path, config: Path, expected: str, fix: str = RESTORE) -> None:
    """Refuse a weights file whose SHA-256 differs from the one its JSON records (one flipped bit is enough)."""
    actual = sha256_of(weights)
    if actual != expected:
        raise UsageError(f"release weights {weights} do not match the weights_sha256 in {config.name} (sha256 "
                         f"{actual[:12]}..., expected {expected[:12]}...): the file is corrupt or changed; {fix}")  # fmt: skip


def check_release_meta(meta: dict, config: Path, hparams: bool = True) -> None:
    """Raise UsageError naming the first key of a release JSON that breaks the schema (``hparams=False``: its top
    level only, which needs no import of the model's class)."""
    where = f"release config {config}"
    if meta.get("format") != FORMAT:
        raise UsageError(f"{where} is not a motiondiff release (format {_shown(meta.get('format'))}, expected "
                         f"{FORMAT}): give the .safetensors of a release made by motiondiff.model_files.release")  # fmt: skip
    unknown = sorted(set(meta) - TOP_KEYS)
    missing = sorted(TOP_KEYS - set(meta))
    if unknown or missing:
        raise UsageError(f"{where}: {_keys_problem(unknown, missing, TOP_KEYS)}; {RESTORE}")
    if meta["class"] not in MODEL_CLASSES:
        raise UsageError(f"{where}: class {_shown(meta['class'])} is not one of {', '.join(MODEL_CLASSES)}; {RESTORE}")
    digest = meta["weights_sha256"]
    if not isinstance(digest, str) or not re.fullmatch(r"[0-9a-f]{64}", digest):
        raise UsageError(f"{where}: weights_sha256 must be 64 lowercase hex digits, got {digest!r}; {RESTORE}")
    if not isinstance(meta["provenance"], dict):
        raise UsageError(f"{where}: provenance must be an object; {RESTORE}")
    if not isinstance(meta["hparams"], dict):
        raise UsageError(f"{where}: hparams must be an object; {RESTORE}")
    if hparams:
        (_check_latent_hparams if meta["class"] == LATENT_CLASS else _check_hparams)(meta["hparams"], where)


def _keys_problem(unknown: list, missing: list, allowed) -> str:
    parts = [f"unknown key {unknown[0]!r}"] if unknown else []
    parts += [f"missing key {missing[0]!r}"] if missing else []
    return ", ".join(parts) + f" (keys: {', '.join(sorted(allowed))})"


def _check_hparams(h: dict, where: str) -> None:
    from motiondiff.lit.motion_diffusion import MotionDiffusion  # lazy: lightning (+4.4 s): a refusal stays quick

    _check_keys(h, MotionDiffusion, where)

    def fail(key: str, want: str):
        raise UsageError(f"{where}: hparams.{key}={_shown(_get(h, key))} must be {want}; {RESTORE}")

    for key in ("feature_dim", "max_frames", "num_joints", "model.d_model", "model.num_layers", "model.num_heads",
                "model.ff_size", "diffusion.steps"):  # fmt: skip
        if not _is_int(_get(h, key)) or _get(h, key) < 1:
            fail(key, "an integer >= 1")
    for key in ("model", "backbone", "condition", "diffusion", "optim"):
        if not isinstance(h[key], dict):
            fail(key, "an object")
    for key in ("representation", "loss", "known_conditioning"):
        if h.get(key) is not None and not isinstance(h[key], dict):
            fail(key, "an object or null")
    if h["model"]["d_model"] % h["model"]["num_heads"]:
        fail("model.num_heads", f"a divisor of model.d_model={h['model']['d_model']}")
    for key in ("backbone.name", "diffusion.prediction", "diffusion.schedule"):
        if not isinstance(_get(h, key), str) or not _get(h, key):
            fail(key, "a non-empty string")
    if not isinstance(h.get("dataset", ""), str):
        fail("dataset", "a string")
    if not _is_number(h["fps"]) or not h["fps"] > 0:
        fail("fps", "a finite number > 0")
    dim = h["feature_dim"]
    for key in ("mean", "std"):
        if not _numbers(h[key], dim):
            fail(key, f"a list of {dim} finite numbers (feature_dim)")
    if not all(s > 0 for s in h["std"]):
        fail("std", "positive everywhere")
    x0 = h.get("x0_range")
    if x0 is not None and not (isinstance(x0, list) and len(x0) == 2 and all(_numbers(r, dim) for r in x0)):
        fail("x0_range", f"null or two lists of {dim} finite numbers")
    kind = _get(h, "condition.kind")
    if kind not in CONDITION_KINDS:
        fail("condition.kind", "one of " + ", ".join(CONDITION_KINDS))
    names = h.get("action_names")
    if names is not None and not (isinstance(names, list) and all(isinstance(n, str) and n for n in names)):
        fail("action_names", "null or a list of names")
    if kind == "action" and not names:
        fail("action_names", "a non-empty list of names for an action model")
    _check_text_encoder(h.get("text_encoder"), kind, where)


def _check_keys(h: dict, cls, where: str, prefix: str = "hparams") -> None:
    """Refuse keys ``cls.__init__`` does not take, and required ones that are missing."""
    params = list(inspect.signature(cls.__init__).parameters.values())[1:]
    every = {p.name for p in params}
    required = {p.name for p in params if p.default is inspect.Parameter.empty}
    unknown, missing = sorted(set(h) - every), sorted(required - set(h))
    if unknown or missing:
        raise UsageError(f"{where}: {prefix} has {_keys_problem(unknown, missing, every)}; {RESTORE}")


def _check_latent_hparams(h: dict, where: str) -> None:
    """A GuidedMotion latent release: its own keys, a VAE per level with finite normalisation, a named encoder."""
    from motiondiff.lit.latent import HierarchicalLatentModule  # lazy: lightning, spacy (+5.1 s to import)

    _check_keys(h, HierarchicalLatentModule, where)

    def fail(key: str, want: str):
        raise UsageError(f"{where}: hparams.{key}={_shown(_get(h, key))} must be {want}; {RESTORE}")

    for key in ("model", "diffusion", "optim", "vaes"):
        if not isinstance(h[key], dict):
            fail(key, "an object")
    if not _is_int(h["node_dim"]) or h["node_dim"] < 1:
        fail("node_dim", "an integer >= 1")
    from motiondiff.lit.vae import MotionVAEModule  # lazy: lightning (+4.4 s to import)

    for level in LEVELS:
        vae = h["vaes"].get(level)
        if not isinstance(vae, dict):
            fail(f"vaes.{level}", "an object (GuidedMotion has a VAE per level)")
        _check_keys(vae, MotionVAEModule, where, f"hparams.vaes.{level}")
        for key in ("feature_dim", "max_frames", "num_joints"):
            if not _is_int(vae[key]) or vae[key] < 1:
                fail(f"vaes.{level}.{key}", "an integer >= 1")
        if not _is_number(vae["fps"]) or not vae["fps"] > 0:
            fail(f"vaes.{level}.fps", "a finite number > 0")
        for key in ("mean", "std"):
            if not _numbers(vae[key], vae["feature_dim"]):
                fail(f"vaes.{level}.{key}", f"a list of {vae['feature_dim']} finite numbers (feature_dim)")
        if not all(s > 0 for s in vae["std"]):
            fail(f"vaes.{level}.std", "positive everywhere")
    _check_text_encoder(h["text_encoder"], "text", where)


def _check_text_encoder(encoder, kind: str, where: str) -> None:

    if encoder is None:
        if kind == "text":
            raise UsageError(f"{where}: a text model's hparams.text_encoder must name its encoder; {RESTORE}")
        return
    if not isinstance(encoder, dict):
        raise UsageError(f"{where}: hparams.text_encoder must be an object or null; {RESTORE}")
    extra = sorted(set(encoder) - ENCODER_KEYS)
    if extra:
        raise UsageError(f"{where}: hparams.text_encoder.{extra[0]} is not allowed (a release names its encoder "
                         f"with name, dim and max_length only, never a path); {RESTORE}")  # fmt: skip
    name = encoder.get("name")
    if name not in TEXT_ENCODERS:
        raise UsageError(f"{where}: hparams.text_encoder.name={_shown(name)} is not a known text encoder (one of "
                         f"{', '.join(TEXT_ENCODERS)}; a release names its encoder, never a path); {RESTORE}")  # fmt: skip
    if not _is_int(encoder.get("dim")) or encoder["dim"] < 1:
        raise UsageError(f"{where}: hparams.text_encoder.dim must be an integer >= 1; {RESTORE}")
    if encoder.get("max_length") is not None and (not _is_int(encoder["max_length"]) or encoder["max_length"] < 1):
        raise UsageError(f"{where}: hparams.text_encoder.max_length must be null or an integer >= 1; {RESTORE}")


def _get(d: dict, dotted: str):
    for part in dotted.split("."):
        d = d.get(part) if isinstance(d, dict) else None
    return d


def _is_int(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def _numbers(values, length: int) -> bool:
    return isinstance(values, list) and len(values) == length and all(_is_number(v) for v in values)


def _shown(value) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _short(err: BaseException) -> str:
    return str(err).splitlines()[0][:160] if str(err) else type(err).__name__
