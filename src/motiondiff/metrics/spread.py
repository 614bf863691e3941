"""Spread and quality of generated motions: Diversity, MultiModality, action accuracy, smoothness."""

from __future__ import annotations

import numpy as np
import torch
from torch import Tensor
from torchmetrics import Metric
from torchmetrics.classification import MulticlassAccuracy

from motiondiff.metrics._base import (
    _check_features,
    _f64,
    _gathered,
    _matrix,
)


# ---- Diversity and MultiModality --------------------------------------------------------------------------------
def diversity(features, num_pairs: int, rng: np.random.Generator | int) -> float:
    """(1/S) Σ_i |x_a(i) - x_b(i)|, S = min(num_pairs, N); a and b are two independent draws of S indices without
    replacement (so a pair may repeat an index and add 0, as in the official code)."""
    x = _matrix(features, "diversity", min_rows=2)
    rng = np.random.default_rng(rng)
    size = min(num_pairs, len(x))
    first = rng.choice(len(x), size, replace=False)
    second = rng.choice(len(x), size, replace=False)
    return float(np.linalg.norm(x[first] - x[second], axis=1).mean())


def multimodality(features, num_pairs: int, rng: np.random.Generator | int) -> float:
    """features [C, R, D]: R generations for each of C conditions. For each condition (in order) draw num_pairs
    first and num_pairs second repeat indices, each without replacement; mean |x_c,a - x_c,b| over pairs and
    conditions."""
    x = _f64(features)
    if x.ndim != 3 or len(x) == 0:
        raise ValueError(f"multimodality: expected features [C, R, D] with C >= 1, got shape {tuple(x.shape)}")
    repeats = x.shape[1]
    if repeats < num_pairs:
        raise ValueError(f"multimodality: needs >= num_pairs={num_pairs} generations per condition, got {repeats}")
    rng = np.random.default_rng(rng)
    dists = []
    for cond in x:
        first = rng.choice(repeats, num_pairs, replace=False)
        second = rng.choice(repeats, num_pairs, replace=False)
        dists.append(np.linalg.norm(cond[first] - cond[second], axis=1))
    return float(np.mean(dists))


class Diversity(Metric):
    """Diversity: mean distance between S = min(num_pairs, N) random pairs of features (``diversity``), the draws
    seeded with ``seed``. 300 pairs for text-to-motion, 200 for action-to-motion. Closer to real is better."""

    full_state_update = False
    is_differentiable = False
    higher_is_better = None  # "→": the generated value should match the real data's

    def __init__(self, num_pairs: int = 300, seed: int = 0, **kwargs):
        super().__init__(**kwargs)
        self.num_pairs, self.seed = num_pairs, seed
        self.add_state("features", [], dist_reduce_fx="cat")

    def update(self, features: Tensor) -> None:
        """features [N, D]."""
        self.features.append(_check_features(features, "Diversity"))

    def compute(self) -> Tensor:
        value = diversity(_gathered(self.features, "Diversity"), self.num_pairs, np.random.default_rng(self.seed))
        return torch.tensor(value, dtype=torch.float64, device=self.device)


class MultiModality(Metric):
    """MultiModality: per condition, mean distance between ``num_pairs`` random pairs of its R generations, then
    the mean over conditions (``multimodality``). 10 pairs of 30 for text-to-motion, 20 for action-to-motion."""

    full_state_update = False
    is_differentiable = False
    higher_is_better = None  # "↑" in MDM's text-to-motion table, "→" (closer to real) in its action-to-motion one

    def __init__(self, num_pairs: int = 10, seed: int = 0, **kwargs):
        super().__init__(**kwargs)
        self.num_pairs, self.seed = num_pairs, seed
        self.add_state("features", [], dist_reduce_fx="cat")

    def update(self, features: Tensor) -> None:
        """features [C, R, D]: R generations for each of C conditions (captions or actions)."""
        if features.ndim != 3:
            raise ValueError(f"MultiModality: expected features [C, R, D], got {tuple(features.shape)}")
        if features.shape[1] < self.num_pairs:
            raise ValueError(
                f"MultiModality: needs >= num_pairs={self.num_pairs} generations per condition, got {features.shape[1]}"
            )
        if self.features and self.features[0].shape[1:] != features.shape[1:]:
            raise ValueError(
                f"MultiModality: every update needs the same [R, D], got {tuple(features.shape[1:])} "
                f"after {tuple(self.features[0].shape[1:])}"
            )
        self.features.append(features.detach().to(torch.float64))

    def compute(self) -> Tensor:
        features = _gathered(self.features, "MultiModality")
        value = multimodality(features, self.num_pairs, np.random.default_rng(self.seed))
        return torch.tensor(value, dtype=torch.float64, device=self.device)


# ---- action accuracy --------------------------------------------------------------------------------------------
class ActionAccuracy(MulticlassAccuracy):
    """Accuracy of the action classifier on generated motion: (1/N) Σ_i 1[argmax_c logits_ic = y_i] (micro).
    ``update(logits [N, C] or predicted labels [N], target [N])``; states are torchmetrics' summed stat scores."""

    def __init__(self, num_classes: int, **kwargs):
        super().__init__(num_classes=num_classes, average="micro", top_k=1, **kwargs)


# ---- smoothness ---------------------------------------------------------------------------------------------------
def smoothness(motion, alpha: float = 1.0) -> float:
    """vvMDM eq. 16 for one clip [T, M]: (1/M) Σ_j (1/(T-2)) Σ_t exp(-alpha |a_j,t|), with the discrete second
    derivative a_t = x[t+2] - 2 x[t+1] + x[t] of each feature j. 1 for motion without acceleration."""
    x = _f64(motion)
    if x.ndim != 2:
        raise ValueError(f"smoothness: expected one clip [T, M], got shape {tuple(x.shape)}")
    if len(x) < 3:
        raise ValueError(f"smoothness: a second derivative needs at least 3 frames, got {len(x)}")
    accel = x[2:] - 2.0 * x[1:-1] + x[:-2]
    return float(np.exp(-alpha * np.abs(accel)).mean())


class Smoothness(Metric):
    """vvMDM eq. 16: Smoothness = 1/(N·M) Σ_i Σ_j (1/(T_i-2)) Σ_t exp(-alpha |a_(i,j),t|), i.e. the mean over the N
    clips of ``smoothness`` of each clip's first T_i frames. ``update(motion [B, T, M], lengths [B] or None)``."""

    full_state_update = False
    is_differentiable = False
    higher_is_better = True

    def __init__(self, alpha: float = 1.0, **kwargs):
        super().__init__(**kwargs)
        self.alpha = alpha
        self.add_state("score_sum", torch.tensor(0.0, dtype=torch.float64), dist_reduce_fx="sum")
        self.add_state("num_clips", torch.tensor(0, dtype=torch.long), dist_reduce_fx="sum")

    def update(self, motion: Tensor, lengths: Tensor | None = None) -> None:
        """motion [B, T, M]; lengths [B]: valid frames of each clip (frames after it are padding), default T."""
        if motion.ndim != 3:
            raise ValueError(f"Smoothness: expected motion [B, T, M], got {tuple(motion.shape)}")
        clips = _f64(motion)
        num, frames = clips.shape[:2]
        lengths = [frames] * num if lengths is None else [int(n) for n in lengths]
        if len(lengths) != num:
            raise ValueError(f"Smoothness: got {len(lengths)} lengths for {num} clips")
        for i, n in enumerate(lengths):
            if not 3 <= n <= frames:
                raise ValueError(f"Smoothness: clip {i} has length {n}; lengths must be in [3, T={frames}]")
            self.score_sum += smoothness(clips[i, :n], self.alpha)
        self.num_clips += num

    def compute(self) -> Tensor:
        if int(self.num_clips) == 0:
            raise ValueError("Smoothness: no clips were given to update()")
        return self.score_sum / self.num_clips
