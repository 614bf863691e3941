"""Prompt coverage: how close a prompt is to what a text model was trained on, and a warning when it is far.

A text model only knows the motions its captions described. A prompt far from every training caption ("a person
jumps forward" to a model that never saw a jump) still produces a motion, and without a word the user cannot tell
it is not what they asked. A release therefore carries a coverage bank beside its weights
(`<stem>.coverage.safetensors`): the text-encoder features of distinct training captions (a fixed number per action),
each caption's action, and the threshold chosen on val captions against out-of-domain text
(docs/results/coverage/rules.md). A prompt whose largest cosine similarity to the bank is below the threshold gets
one warning line naming the nearest known actions.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from motiondiff.runtime.atomic import atomic_write

COVERAGE_SUFFIX = ".coverage.safetensors"


def coverage_path(model_path: str | Path) -> Path:
    """The coverage bank of a release (`x.safetensors` or `x.json` -> `x.coverage.safetensors`)."""
    path = Path(model_path)
    return path.with_name(path.name.split(".")[0] + COVERAGE_SUFFIX)


def _unit(rows: np.ndarray) -> np.ndarray:
    rows = np.asarray(rows, dtype=np.float32)
    return rows / np.maximum(np.linalg.norm(rows, axis=-1, keepdims=True), 1e-12)


@dataclass(frozen=True)
class CoverageReport:
    """One prompt against the bank: its best similarity, the nearest actions (name, similarity), far or not."""

    prompt: str
    similarity: float
    nearest: list[tuple[str, float]]
    threshold: float

    @property
    def far(self) -> bool:
        return self.similarity < self.threshold

    def warning(self) -> str:
        near = ", ".join(f"{name} ({sim:.2f})" for name, sim in self.nearest)
        return (f"{self.prompt!r} is far from everything this model was trained on (closest caption similarity "
                f"{self.similarity:.2f} < {self.threshold:.2f}); nearest known actions: {near}. The motion may not "
                "be what you asked")  # fmt: skip


@dataclass(frozen=True)
class PromptCoverage:
    """Unit caption features (K, E), the action index of each (K,), the action names, the threshold, the encoder."""

    features: np.ndarray
    actions: np.ndarray
    action_names: list[str]
    threshold: float
    encoder: str

    def similarities(self, prompt_features: np.ndarray) -> np.ndarray:
        """(P, K) cosine similarity of each prompt to each bank caption."""
        return _unit(prompt_features) @ self.features.T

    def best(self, prompt_features: np.ndarray) -> np.ndarray:
        """(P,) each prompt's largest similarity to the bank."""
        return self.similarities(prompt_features).max(axis=1)

    def check(self, prompts: list[str], prompt_features: np.ndarray, top: int = 3) -> list[CoverageReport]:
        sims = self.similarities(prompt_features)
        reports = []
        for prompt, row in zip(prompts, sims, strict=True):
            per_action = np.full(len(self.action_names), -np.inf)
            np.maximum.at(per_action, self.actions, row)
            order = [int(i) for i in np.argsort(-per_action)[:top] if np.isfinite(per_action[i])]
            nearest = [(self.action_names[i], float(per_action[i])) for i in order]
            reports.append(CoverageReport(prompt, float(row.max()), nearest, self.threshold))
        return reports

    def save(self, path: str | Path) -> Path:
        from safetensors.numpy import save_file

        meta = {"action_names": json.dumps(self.action_names), "threshold": repr(float(self.threshold)),
                "encoder": self.encoder}  # fmt: skip
        tensors = {"features": self.features.astype(np.float16), "actions": self.actions.astype(np.int32)}
        atomic_write(Path(path), lambda tmp: save_file(tensors, str(tmp), metadata=meta), suffix=".safetensors")
        return Path(path)

    @classmethod
    def load(cls, path: str | Path) -> PromptCoverage:
        """A saved bank (safetensors: no code runs). A broken file is a ValueError naming it."""
        from safetensors import safe_open

        try:
            with safe_open(str(path), framework="numpy") as f:
                meta = f.metadata() or {}
                features, actions = f.get_tensor("features"), f.get_tensor("actions")
            names = json.loads(meta["action_names"])
            threshold = float(meta["threshold"])
        except Exception as err:  # noqa: BLE001 - any damage is one message naming the file
            raise ValueError(f"coverage bank {path} cannot be read ({type(err).__name__}: {err}); delete it or "
                             "rebuild it with python -m motiondiff.studies.prompt_coverage") from None  # fmt: skip
        features = features.astype(np.float32)
        if features.ndim != 2 or actions.shape != (len(features),) or not np.isfinite(features).all():
            raise ValueError(f"coverage bank {path}: features {features.shape} / actions {actions.shape} do not match")
        if len(actions) and (actions.min() < 0 or actions.max() >= len(names)) or not np.isfinite(threshold):
            raise ValueError(f"coverage bank {path}: action indices or threshold out of range")
        return cls(_unit(features), actions.astype(np.int64), list(names), threshold, meta.get("encoder", ""))


def build_coverage(captions: dict[str, list[str]], encode, threshold: float, encoder: str, per_action: int = 128,
                   seed: int = 0) -> PromptCoverage:  # fmt: skip
    """A bank of at most `per_action` distinct captions per action (drawn with `seed`), encoded with `encode`
    (list[str] -> (N, E) array)."""
    rng = np.random.default_rng(seed)
    names = sorted(captions)
    texts, actions = [], []
    for index, name in enumerate(names):
        distinct = sorted(set(captions[name]))
        pick = distinct if len(distinct) <= per_action else [distinct[i] for i in
                                                              sorted(rng.choice(len(distinct), per_action, replace=False))]  # fmt: skip
        texts += pick
        actions += [index] * len(pick)
    features = _unit(np.asarray(encode(texts)))
    return PromptCoverage(features, np.asarray(actions, dtype=np.int64), names, float(threshold), encoder)


def choose_threshold(in_domain: np.ndarray, out_of_domain: np.ndarray) -> tuple[float, float]:
    """(threshold, balanced accuracy): the value maximising balanced accuracy of 'in-domain >= t > out-of-domain';
    where a range of values ties, its midpoint (docs/results/coverage/rules.md)."""
    in_domain, out_of_domain = np.sort(np.asarray(in_domain)), np.sort(np.asarray(out_of_domain))
    candidates = np.unique(np.concatenate([in_domain, out_of_domain, [1.0 + 1e-6]]))
    kept = 1.0 - np.searchsorted(in_domain, candidates, side="left") / len(in_domain)  # in-domain >= t
    warned = np.searchsorted(out_of_domain, candidates, side="left") / len(out_of_domain)  # ood < t
    balanced = (kept + warned) / 2
    best = balanced.max()
    tied = np.flatnonzero(np.isclose(balanced, best))
    # balanced accuracy at a candidate c_i holds on the interval (c_{i-1}, c_i]: the first run of tied candidates
    # c_first..c_last covers (c_{first-1}, c_last], whose midpoint is returned
    tied = set(np.flatnonzero(np.isclose(balanced, best)).tolist())
    first = min(tied)
    last = first
    while last + 1 in tied:
        last += 1
    lower = candidates[first - 1] if first > 0 else candidates[first]
    return float((lower + candidates[last]) / 2), float(best)
