"""Evaluator files: the official checkpoints of the text-motion evaluator and the HumanAct12 classifier, and the
evaluators this project releases (safetensors + JSON config with the weights' SHA-256, no pickle)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import torch
from safetensors.torch import load_file, save_file
from torch import nn

from motiondiff.model_files.release_checks import check_weights_checksum, read_release_json, sha256_of
from motiondiff.models.evaluators.networks import OFFICIAL_MAX_FRAMES, ActionClassifierGRU, TextMotionEvaluator
from motiondiff.runtime.atomic import atomic_write, write_json
from motiondiff.runtime.checked_loading import check_finite_state, reading, torch_load
from motiondiff.runtime.errors import UsageError
from motiondiff.text.word_vectors import load_glove


def load_official_t2m_evaluator(
    checkpoint: str | Path, glove_dir: str | Path, mean, std, dataset: str = "t2m"
) -> TextMotionEvaluator:
    """The official evaluator: `<dataset>/text_mot_match/model/finest.tar`, the `glove/` folder, and the evaluator's
    Mean/Std (paths of `<dataset>/Comp_v6_KLD01/meta/{mean,std}.npy`, or arrays). dataset: "t2m" (HumanML3D, 263)
    or "kit" (251)."""
    dims = {"t2m": 263, "kit": 251}
    if dataset not in dims:
        raise ValueError(f"dataset={dataset!r}: the official evaluators exist for 't2m' (HumanML3D) and 'kit'")
    vocab, vectors = load_glove(glove_dir)
    model = TextMotionEvaluator(dims[dataset], vocab.words, word_dim=vectors.shape[1], learned_words=False)
    model.word_vectors.weight.data.copy_(torch.from_numpy(vectors))
    state = torch_load(checkpoint, "official evaluator", "give the official text_mot_match/model/finest.tar")
    for name in ("movement_encoder", "text_encoder", "motion_encoder"):
        if name not in state:
            raise KeyError(f"{checkpoint} has no {name!r}: is it the text_mot_match finest.tar?")
        getattr(model, name).load_state_dict(state[name], strict=True)
    model.pad_to = OFFICIAL_MAX_FRAMES
    model.set_normalisation(*(np.load(s) if isinstance(s, (str, Path)) else s for s in (mean, std)))
    return model.eval()


def load_official_action_classifier(path: str | Path) -> ActionClassifierGRU:
    """The official HumanAct12 classifier (`action_recognition_model_humanact12.tar`; keys model/optimizer/...)."""
    state = torch_load(path, "official action classifier", "give action_recognition_model_humanact12.tar")
    weights = state.get("model", state)
    model = ActionClassifierGRU(
        input_size=weights["recurrent.weight_ih_l0"].shape[1],
        hidden_size=weights["recurrent.weight_hh_l0"].shape[1],
        num_layers=sum(k.startswith("recurrent.weight_ih_l") for k in weights),
        num_classes=weights["linear2.weight"].shape[0],
        feature_size=weights["linear1.weight"].shape[0],
    )
    model.load_state_dict(weights, strict=True)
    return model.eval()


# ---- released evaluators: safetensors + JSON config -------------------------------------------------------------
_KINDS = {"text_motion": TextMotionEvaluator, "action": ActionClassifierGRU}
EVALUATOR_FIX = "restore the shipped evaluators (`git checkout -- checkpoints`) or rebuild them with `python -m motiondiff.cli.train_evaluator`"


def save_released(model: nn.Module, path: str | Path, meta: dict | None = None) -> Path:
    """`<path>.safetensors` (weights) and `<path>.json` (kind, constructor config, vocabulary, provenance, and the
    weights' SHA-256, checked on load)."""
    path = Path(path)
    kind = next(k for k, cls in _KINDS.items() if isinstance(model, cls))
    config = dict(model.config)
    if isinstance(model, TextMotionEvaluator):
        config["words"] = model.words
    state = {k: v.detach().contiguous().cpu() for k, v in model.state_dict().items()}
    atomic_write(path.with_suffix(".safetensors"), lambda tmp: save_file(state, tmp))
    doc = {
        "kind": kind,
        "config": config,
        "meta": meta or {},
        "weights_sha256": sha256_of(path.with_suffix(".safetensors")),
    }
    write_json(path.with_suffix(".json"), doc)
    return path.with_suffix(".safetensors")


def load_released(path: str | Path) -> tuple[nn.Module, dict]:
    """A released evaluator (no pickle anywhere) -> (model in eval mode, meta). A file that is not one, was changed
    after release (its weights_sha256) or holds NaN weights is one UsageError: its scores would be meaningless."""
    path = Path(path)
    weights, config_file = path.with_suffix(".safetensors"), path.with_suffix(".json")
    for p in (weights, config_file):
        if not p.is_file():
            raise FileNotFoundError(f"{p} not found: {EVALUATOR_FIX}")
    doc = read_release_json(config_file)
    if doc.get("kind") not in _KINDS or not isinstance(doc.get("config"), dict):
        raise UsageError(f"evaluator config {config_file} is not a released evaluator (kind {doc.get('kind')!r}, one "
                         f"of {', '.join(_KINDS)}, and a config object); {EVALUATOR_FIX}")  # fmt: skip
    if not isinstance(doc.get("weights_sha256"), str):
        raise UsageError(f"evaluator config {config_file} records no weights_sha256 (released before checksums); "
                         f"{EVALUATOR_FIX}")  # fmt: skip
    check_weights_checksum(weights, config_file, doc["weights_sha256"], EVALUATOR_FIX)
    with reading(weights, "evaluator weights", EVALUATOR_FIX):
        state = load_file(weights)
        check_finite_state(state, f"evaluator weights {weights}", EVALUATOR_FIX)
        model = _KINDS[doc["kind"]](**doc["config"])
        model.load_state_dict(state, strict=True)
    return model.eval(), doc.get("meta", {})
