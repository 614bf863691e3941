"""The evaluation protocol shared by `evaluate.py` and the training callback (MDM appendix B).

Real clips of a split are fixed once (`EvalClips`); generated motions use their ground-truth lengths and their
captions or action labels; both go through the same evaluators (`Evaluators`), and one replication's metrics come
from `replication_metrics`. Which metrics depend on the condition:

- text: R-precision top-1/2/3, FID, MM-Dist, Diversity (+ MultiModality) on the text-motion evaluator's features;
  where the dataset has action labels and an action classifier, also the action accuracy of motion generated from
  captions: does the motion perform the action its caption names (`action_accuracy`)?
- action: FID, accuracy, Diversity (+ MultiModality) on the action classifier's features;
- none (unconstrained, MoDi/vvMDM protocol): FID, KID, precision, recall, Diversity on the action classifier's
  features when there is one (else the text-motion evaluator's), and smoothness of the generated features.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch

from motiondiff import metrics as M
from motiondiff.data.datasets import MotionDataset
from motiondiff.data.representations.hml_features import features_from_joints, joints_from_features, skeleton_for_dim
from motiondiff.data.representations.spec import bridge_from_spec
from motiondiff.edit.smoothing import smooth_features
from motiondiff.lit.generation import generate_features
from motiondiff.model_files.evaluators import load_released
from motiondiff.models.evaluators.networks import ActionClassifierGRU, TextMotionEvaluator, motion_input

log = logging.getLogger(__name__)
TEXT_MOTION, ACTION = "text_motion", "action"


@dataclass
class EvalClips:
    """Real clips of one split as the evaluation sees them: de-normalised features cropped like the dataset does."""

    ids: list[str]
    features: list[np.ndarray]  # (N_i, D) de-normalised
    captions: list[list[str]]
    actions: np.ndarray  # (C,) label ids, -1 = none
    tokens: dict[str, list[str]] = field(
        default_factory=dict
    )  # caption -> its "word/POS" tokens, where the data has them

    @classmethod
    def from_dataset(cls, ds: MotionDataset, max_clips: int | None = None, seed: int = 0) -> EvalClips:
        """All clips, or a fixed random subset of `max_clips` (same subset every time for a seed)."""
        index = np.arange(len(ds))
        if max_clips is not None and max_clips < len(ds):
            index = np.sort(np.random.default_rng(seed).choice(len(ds), max_clips, replace=False))
        ids, feats, caps, acts, tokens = [], [], [], [], {}
        for i in index:
            rec = ds.records[int(i)]
            n = min(rec.length, ds.max_frames)
            n = max(ds.unit_length, n - n % ds.unit_length)
            ids.append(rec.id)
            feats.append(rec.motion[:n].astype(np.float32))
            caps.append(list(rec.texts))
            acts.append(rec.action)
            for text, toks in zip(rec.texts, rec.meta.get("tokens") or [], strict=False):
                tokens.setdefault(text, list(toks))
        return cls(ids, feats, caps, np.array(acts), tokens)

    def __len__(self) -> int:
        return len(self.ids)

    @property
    def lengths(self) -> torch.Tensor:
        return torch.tensor([len(f) for f in self.features])

    def pick_captions(self, rng: np.random.Generator) -> list[str]:
        """One caption per clip, drawn at random (the official loader draws one per motion each time)."""
        return [c[int(rng.integers(len(c)))] if c else "" for c in self.captions]

    def label_captions(self) -> list[str]:
        """Each clip's first caption: for generated captions the one built from the labels alone, which names the
        action (motiondiff.data.preparing.captions), so the action-accuracy metric asks for exactly the labelled action."""
        return [c[0] if c else "" for c in self.captions]

    @property
    def labelled(self) -> bool:
        return bool((self.actions >= 0).any())


def pad(features: list[np.ndarray]) -> tuple[torch.Tensor, torch.Tensor]:
    lengths = torch.tensor([len(f) for f in features])
    out = torch.zeros(len(features), int(lengths.max()), features[0].shape[1])
    for i, f in enumerate(features):
        out[i, : len(f)] = torch.as_tensor(f)
    return out, lengths


class Evaluators:
    """The evaluators of one dataset: a text-motion matching model and/or an action classifier."""

    def __init__(self, text_motion: TextMotionEvaluator | None = None, action: ActionClassifierGRU | None = None,
                 num_joints: int = 22, meta: dict | None = None, batch_size: int = 128):  # fmt: skip
        if text_motion is None and action is None:
            raise ValueError("Evaluators needs a text-motion evaluator, an action classifier or both")
        self.text_motion, self.action, self.num_joints = text_motion, action, num_joints
        self.meta = meta or {}
        self.batch_size = batch_size
        # Features of another representation -> the HumanML3D features the evaluators read (None: already those).
        self.bridge: Callable[[np.ndarray], np.ndarray] | None = None
        # An official classifier that reads the model's own features (24 SMPL joints or rotations, see
        # motiondiff.eval.official): called on them directly instead of on the HumanML3D bridge.
        self.action_reader: Callable[[list[np.ndarray]], tuple[torch.Tensor, torch.Tensor]] | None = None

    def for_module(self, module) -> Evaluators:
        """Read the features of `module`'s representation (real clips and samples go through the same bridge)."""
        bridge = bridge_from_spec(module.hparams.get("representation"), module.hparams.feature_dim)
        self.bridge = None if bridge.identity else bridge
        return self

    @classmethod
    def load(cls, folder: str | Path, num_joints: int = 22) -> Evaluators:
        """Released evaluators of a dataset: `<folder>/text_motion.{safetensors,json}`, `<folder>/action.*`."""
        folder = Path(folder)
        found = {k: folder / f"{k}.safetensors" for k in (TEXT_MOTION, ACTION)}
        found = {k: p for k, p in found.items() if p.is_file()}
        if not found:
            raise FileNotFoundError(
                f"no evaluator in {folder}: train one with `python -m motiondiff.cli.train_evaluator "
                f"dataset=<name>` (or point evaluator.dir at a folder with text_motion/action .safetensors)"
            )
        models, meta = {}, {}
        for kind, path in found.items():
            models[kind], meta[kind] = load_released(path)
        return cls(models.get(TEXT_MOTION), models.get(ACTION), num_joints, meta)

    def as_hml(self, features: list[np.ndarray]) -> list[np.ndarray]:
        """The HumanML3D features the evaluators read (smoothness is measured on them too, so that models with
        different representations are compared in one feature space)."""
        return features if self.bridge is None else [self.bridge(f) for f in features]

    @torch.inference_mode()
    def embed_motion(self, features: list[np.ndarray]) -> dict[str, np.ndarray]:
        """De-normalised features of clips -> {"text_motion": (C, E), "action_features": (C, F), "action_logits"}."""
        out: dict[str, list] = {}
        reads_hml = self.text_motion is not None or (self.action is not None and self.action_reader is None)
        hml = self.as_hml(features) if reads_hml else None  # an official reader alone needs no bridge
        for s in range(0, len(features), self.batch_size):
            if reads_hml:
                x, lengths = pad(hml[s : s + self.batch_size])
            if self.text_motion is not None:
                out.setdefault("text_motion", []).append(self.text_motion.encode_motion(x, lengths))
            if self.action_reader is not None:
                logits, feats = self.action_reader(features[s : s + self.batch_size])
            elif self.action is not None:
                logits, feats = self.action(motion_input(self.action, x, self.num_joints), lengths)
            if self.action is not None:
                out.setdefault("action_features", []).append(feats)
                out.setdefault("action_logits", []).append(logits)
        return {k: torch.cat(v).double().numpy() for k, v in out.items()}

    @torch.inference_mode()
    def embed_text(self, captions: list[str]) -> np.ndarray:
        if self.text_motion is None:
            raise ValueError("text metrics need a text-motion evaluator; this dataset's evaluators have none")
        parts = [self.text_motion.encode_text(captions[s : s + self.batch_size])
                 for s in range(0, len(captions), self.batch_size)]  # fmt: skip
        return torch.cat(parts).double().numpy()

    @property
    def action_names(self) -> list[str]:
        """The action classifier's label names, in its output order."""
        if self.action is None:
            raise ValueError("these evaluators have no action classifier")
        return list(self.meta["action"]["action_names"])

    def measures_action(self, kind: str, clips: EvalClips) -> bool:
        """Whether motion of this condition kind for these clips gets an action accuracy: text models on labelled
        data with an action classifier (does the motion do the action its caption names?)."""
        return kind == "text" and self.action is not None and clips.labelled

    def fid_features(self, kind: str) -> str:
        """Which embedding FID/diversity use for a condition kind."""
        if kind == "text":
            return TEXT_MOTION
        if kind == "action" or self.action is not None:
            if self.action is None:
                raise ValueError("action-conditioned evaluation needs an action classifier for this dataset")
            return "action_features"
        return TEXT_MOTION


def replication_metrics(
    kind: str,
    evaluators: Evaluators,
    real: dict[str, np.ndarray],
    generated: dict[str, np.ndarray],
    text: np.ndarray | None = None,
    actions: np.ndarray | None = None,
    generated_features: list[np.ndarray] | None = None,
    own_features: list[np.ndarray] | None = None,
    diversity_pairs: int = 300,
    pool_size: int = 32,
    knn_k: int = 3,
    smoothness_alpha: float = 1.0,
    seed: int = 0,
) -> dict[str, float]:
    """Metrics of one replication. `real`/`generated` are `Evaluators.embed_motion` outputs; `text` the caption
    embeddings matched row by row with `generated`; `actions` the labels the motions were generated from."""
    key = evaluators.fid_features(kind)
    real_f, gen_f = real[key], generated[key]
    out = {"fid": M.frechet_distance(*M.gaussian_statistics(real_f), *M.gaussian_statistics(gen_f))}
    out["diversity"] = M.diversity(gen_f, diversity_pairs, np.random.default_rng(seed))
    if kind == "text":
        for name, value in M.r_precision(text, generated[TEXT_MOTION], top_k=3, pool_size=pool_size).items():
            out[f"r_precision_{name}"] = value
        out["mm_dist"] = M.mm_dist(text, generated[TEXT_MOTION])
    elif kind == "action":
        out["accuracy"] = float((generated["action_logits"].argmax(-1) == actions).mean())
    else:
        kid = M.kid(real_f, gen_f, rng=np.random.default_rng(seed))
        out["kid"] = kid["mean"]
        out.update(M.knn_precision_recall(real_f, gen_f, k=knn_k))
    if generated_features is not None:
        out["smoothness"] = float(np.mean([M.smoothness(f, smoothness_alpha) for f in generated_features]))
    if own_features is not None:  # vvMDM Fig. 2: on the representation's own features, not the HumanML3D bridge
        out["smoothness_own"] = float(np.mean([M.smoothness(f, smoothness_alpha) for f in own_features]))
    return out


def action_accuracy(evaluators: Evaluators, generated: dict[str, np.ndarray], actions: np.ndarray) -> float:
    """Share of motions the dataset's action classifier assigns the label of the clip they were generated for
    (clips without a label are left out)."""
    if "action_logits" not in generated:
        raise ValueError("action accuracy needs the dataset's action classifier; its evaluators have none")
    actions = np.asarray(actions)
    keep = actions >= 0
    if not keep.any():
        raise ValueError("action accuracy needs action labels; none of these clips has one")
    return float((generated["action_logits"].argmax(-1)[keep] == actions[keep]).mean())


def multimodality(embeddings: np.ndarray, num_pairs: int = 10, seed: int = 0) -> float:
    """(C conditions, R repeats, E) embeddings of repeated generations -> MultiModality."""
    return M.multimodality(embeddings, num_pairs, np.random.default_rng(seed))


def generate(
    module,
    conditions: list,
    lengths: torch.Tensor,
    batch_size: int = 64,
    generator: torch.Generator | None = None,
    progress=None,
    precision: str = "32-true",
    smooth_sigma: float | None = None,
    **sampling,
) -> list[np.ndarray]:
    """De-normalised generated features, one per condition (caption, action id or None), at the given lengths
    (`motiondiff.lit.generation.generate_features`), with vvMDM's temporal filter when `smooth_sigma` > 0 (HumanML3D
    or jp features; ``edit.smoothing.smooth_features``), so the metrics see what sample.py saves."""

    feats = generate_features(module, conditions, lengths, batch_size, generator, progress, precision, **sampling)
    layout = getattr(getattr(module, "representation", None), "name", "hml263")
    return [smooth_features(f, smooth_sigma, layout) for f in feats]


def time_reversed(features: np.ndarray, num_joints: int) -> np.ndarray:
    """The same clip played backwards, re-encoded (velocities and contacts recomputed): a motion every evaluator
    should tell apart from the original (walking forward becomes walking backward)."""

    joints = joints_from_features(features, num_joints)[::-1]
    return features_from_joints(np.ascontiguousarray(joints), skeleton_for_dim(features.shape[-1]))
