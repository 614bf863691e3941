"""Input checks, distance helpers and the real-vs-generated feature states shared by the metrics."""

from __future__ import annotations

import numpy as np
import torch
from torch import Tensor
from torchmetrics import Metric
from torchmetrics.utilities.data import dim_zero_cat

_CHUNK = 2048  # rows of a distance matrix held at once (2048 x 10k float64 = 160 MB)


# ---- helpers ----------------------------------------------------------------------------------------------------
def _f64(x) -> np.ndarray:
    """A tensor (any device) or array-like as a float64 numpy array."""
    if isinstance(x, Tensor):
        x = x.detach().cpu().to(torch.float64).numpy()
    return np.asarray(x, dtype=np.float64)


def _matrix(x, what: str, min_rows: int = 1) -> np.ndarray:
    arr = _f64(x)
    if arr.ndim != 2:
        raise ValueError(f"{what}: expected a 2-D [N, D] array, got shape {tuple(arr.shape)}")
    if len(arr) < min_rows:
        raise ValueError(f"{what}: needs at least {min_rows} samples, got {len(arr)}")
    return arr


def _pairs(text, motion, what: str, min_rows: int = 1) -> tuple[np.ndarray, np.ndarray]:
    t, m = _matrix(text, f"{what} text", min_rows), _matrix(motion, f"{what} motion", min_rows)
    if t.shape != m.shape:
        raise ValueError(f"{what}: text and motion embeddings must pair row by row, got {t.shape} and {m.shape}")
    return t, m


def _cdist(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Euclidean distances [len(a), len(b)], from the differences themselves rather than |a|²+|b|²-2a·b, so equal
    points are exactly 0 apart and ties stay ties."""
    a, b = torch.from_numpy(np.ascontiguousarray(a)), torch.from_numpy(np.ascontiguousarray(b))
    return torch.cdist(a, b, compute_mode="donot_use_mm_for_euclid_dist").numpy()


def _gathered(state: list[Tensor] | Tensor, what: str) -> Tensor:
    """A "cat" state as one tensor (a list before the sync, a tensor after it), or a clear error when empty."""
    if (isinstance(state, list) and not state) or (isinstance(state, Tensor) and state.numel() == 0):
        raise ValueError(f"{what}: no samples were given to update()")
    return dim_zero_cat(state)


def _check_features(features: Tensor, what: str) -> Tensor:
    if features.ndim != 2:
        raise ValueError(f"{what}: expected features of shape [N, D], got {tuple(features.shape)}")
    return features.detach().to(torch.float64)


class _TwoStates(Metric):
    """Accumulates two sets of feature rows in two "cat" states: ``STATES`` = ((state, what it holds), ...)."""

    full_state_update = False
    is_differentiable = False
    STATES: tuple[tuple[str, str], tuple[str, str]]

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        for state, _ in self.STATES:
            self.add_state(state, [], dist_reduce_fx="cat")

    def _both(self) -> tuple[Tensor, Tensor]:
        name = type(self).__name__
        first, second = (_gathered(getattr(self, state), f"{name} {what}") for state, what in self.STATES)
        return first, second


class _RealVsGenerated(_TwoStates):
    """Features of real and of generated samples."""

    STATES = (("real_features", "real"), ("fake_features", "generated"))

    def update(self, features: Tensor, real: bool) -> None:
        """features [N, D]: of real samples when ``real`` is true, of generated ones otherwise."""
        features = _check_features(features, type(self).__name__)
        (self.real_features if real else self.fake_features).append(features)
