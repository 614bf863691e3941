"""Text-motion matching: R-precision and MM-Dist."""

from __future__ import annotations

import numpy as np
import torch
from torch import Tensor

from motiondiff.metrics._base import (
    _cdist,
    _check_features,
    _pairs,
    _TwoStates,
)


# ---- R-Precision and MM Dist ------------------------------------------------------------------------------------
def r_precision_counts(text, motion, top_k: int = 3) -> np.ndarray:
    """For one pool of matched pairs (text row i describes motion row i): counts[k-1] = how many texts have their
    own motion among their k nearest motions (Euclidean), k = 1..top_k. Ties are broken by row order (stable sort).
    This is the official T2M/MDM direction (distance matrix text x motion, sorted per row), so numbers compare with
    published ones."""
    t, m = _pairs(text, motion, "r_precision_counts")
    order = np.argsort(_cdist(t, m), axis=1, kind="stable")  # per text: motions, nearest first
    rank = np.argmax(order == np.arange(len(t))[:, None], axis=1)  # 0-based place of the matched motion
    return np.array([int((rank < k).sum()) for k in range(1, top_k + 1)])


def r_precision(text, motion, top_k: int = 3, pool_size: int = 32) -> dict[str, float]:
    """Top-k retrieval accuracy of the matched text in pools of ``pool_size`` consecutive pairs (chance k/pool).

    A trailing partial pool is dropped, as the official loader's ``drop_last=True`` batches of 32 do, unless it is
    the only pool: fewer than ``pool_size`` pairs (≥ 2) make one pool of all of them (chance then k/N).
    """
    t, m = _pairs(text, motion, "r_precision", min_rows=2)
    n = len(t)
    size = pool_size if n >= pool_size else n
    used = n - n % size
    counts = sum(r_precision_counts(t[s : s + size], m[s : s + size], top_k) for s in range(0, used, size))
    return {f"top{k}": float(counts[k - 1]) / used for k in range(1, top_k + 1)}


def mm_dist(text, motion) -> float:
    """Mean Euclidean distance between matched rows: (1/N) Σ_i |text_i - motion_i|."""
    t, m = _pairs(text, motion, "mm_dist")
    return float(np.linalg.norm(t - m, axis=1).mean())


class _TextMotionPairs(_TwoStates):
    """Matched (text, motion) embedding pairs, in order."""

    STATES = (("text", "text"), ("motion", "motion"))

    def update(self, text_emb: Tensor, motion_emb: Tensor) -> None:
        """text_emb, motion_emb [N, D]: row i of each is a matched pair."""
        name = type(self).__name__
        if text_emb.shape != motion_emb.shape:
            raise ValueError(
                f"{name}: text and motion embeddings must pair row by row, got {tuple(text_emb.shape)} "
                f"and {tuple(motion_emb.shape)}"
            )
        self.text.append(_check_features(text_emb, name))
        self.motion.append(_check_features(motion_emb, name))


class RPrecision(_TextMotionPairs):
    """R-Precision (Guo et al. 2022): per caption, rank its own motion among the motions of its pool of
    ``pool_size`` consecutive pairs by Euclidean distance (the official code's direction); top-k = fraction ranked within the first k, for k = 1..top_k (``r_precision``). ``compute()`` -> {"top1": , ..., f"top{top_k}": }. Pools are formed from the
    pairs in update order (after a DDP sync: rank 0's pairs, then rank 1's, ...)."""

    higher_is_better = True

    def __init__(self, top_k: int = 3, pool_size: int = 32, **kwargs):
        super().__init__(**kwargs)
        if top_k < 1 or pool_size < 2:
            raise ValueError(f"RPrecision: need top_k >= 1 and pool_size >= 2, got {top_k} and {pool_size}")
        self.top_k, self.pool_size = top_k, pool_size

    def compute(self) -> dict[str, Tensor]:
        scores = r_precision(*self._both(), top_k=self.top_k, pool_size=self.pool_size)
        return {key: torch.tensor(v, dtype=torch.float64, device=self.device) for key, v in scores.items()}


class MMDist(_TextMotionPairs):
    """Multimodal distance: (1/N) Σ_i |text_i - motion_i| over all matched pairs (``mm_dist``)."""

    higher_is_better = False

    def compute(self) -> Tensor:
        return torch.tensor(mm_dist(*self._both()), dtype=torch.float64, device=self.device)
