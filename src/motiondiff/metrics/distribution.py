"""Distances between the real and generated feature distributions: FID, KID, k-NN precision/recall."""

from __future__ import annotations

from collections.abc import Callable
from functools import partial

import numpy as np
import scipy.linalg
import torch
from torch import Tensor

from motiondiff.metrics._base import (
    _CHUNK,
    _cdist,
    _f64,
    _matrix,
    _RealVsGenerated,
)


# ---- FID ----------------------------------------------------------------------------------------------------------
def gaussian_statistics(features) -> tuple[np.ndarray, np.ndarray]:
    """(mean, covariance) of [N, D] features; covariance with ddof=1 (np.cov), as the official T2M/MDM code."""
    x = _matrix(features, "gaussian_statistics", min_rows=2)
    return x.mean(axis=0), np.atleast_2d(np.cov(x, rowvar=False))


def _sqrtm_of_product(sigma1: np.ndarray, sigma2: np.ndarray, imag_tol: float = 1e-3) -> np.ndarray | None:
    root = scipy.linalg.sqrtm(sigma1 @ sigma2)
    if not np.isfinite(root).all() or np.abs(np.diagonal(root).imag).max() > imag_tol:
        return None
    return root.real  # round-off leaves a tiny imaginary part on a product of PSD matrices


def frechet_distance(mu1, sigma1, mu2, sigma2, eps: float = 1e-6) -> float:
    """d² = |mu1 - mu2|² + tr(sigma1 + sigma2 - 2 (sigma1 sigma2)^½) between N(mu1, sigma1) and N(mu2, sigma2)."""
    mu1, mu2 = np.atleast_1d(_f64(mu1)), np.atleast_1d(_f64(mu2))
    sigma1, sigma2 = np.atleast_2d(_f64(sigma1)), np.atleast_2d(_f64(sigma2))
    if mu1.shape != mu2.shape or sigma1.shape != sigma2.shape or sigma1.shape != (len(mu1), len(mu1)):
        raise ValueError(f"frechet_distance: shapes disagree: {mu1.shape}, {sigma1.shape}, {mu2.shape}, {sigma2.shape}")
    covmean = _sqrtm_of_product(sigma1, sigma2)
    if covmean is None:
        # singular covariances (fewer samples than dimensions) can defeat sqrtm; a tiny ridge makes them definite
        ridge = eps * np.eye(len(mu1))
        covmean = _sqrtm_of_product(sigma1 + ridge, sigma2 + ridge)
    if covmean is None:
        raise ValueError(f"frechet_distance: sqrtm(sigma1 @ sigma2) is not finite and real even with eps={eps} added")
    diff = mu1 - mu2
    return float(diff @ diff + np.trace(sigma1) + np.trace(sigma2) - 2.0 * np.trace(covmean))


class FID(_RealVsGenerated):
    """Fréchet Inception-style distance: ``frechet_distance`` of N(mu, Σ) fitted to real and to generated features
    (mean, np.cov with ddof=1). ``update(features, real)``; ``compute()`` -> scalar. Needs ≥ 2 samples per set."""

    higher_is_better = False

    def compute(self) -> Tensor:
        real, fake = self._both()
        for name, feats in (("real", real), ("generated", fake)):
            if len(feats) < 2:
                raise ValueError(f"FID: a covariance needs at least 2 {name} samples, got {len(feats)}")
        value = frechet_distance(*gaussian_statistics(real), *gaussian_statistics(fake))
        return torch.tensor(value, dtype=torch.float64, device=self.device)


# ---- KID ----------------------------------------------------------------------------------------------------------
def polynomial_kernel(x, y, degree: int = 3, gamma: float | None = None, coef: float = 1.0) -> np.ndarray:
    """k(x, y) = (gamma x·y + coef)^degree for all rows of x and y; gamma defaults to 1/D."""
    x, y = _f64(x), _f64(y)
    gamma = 1.0 / x.shape[1] if gamma is None else gamma
    return (gamma * (x @ y.T) + coef) ** degree


def mmd2_unbiased(real, fake, kernel: Callable[[np.ndarray, np.ndarray], np.ndarray]) -> float:
    """Unbiased MMD² (Gretton et al. 2012): mean of k over distinct real pairs + mean over distinct fake pairs
    - 2 x mean over all real-fake pairs; ``kernel(a, b)`` returns the Gram matrix [len(a), len(b)]."""
    x, y = _matrix(real, "mmd2_unbiased real", 2), _matrix(fake, "mmd2_unbiased fake", 2)
    m, n = len(x), len(y)
    k_xx, k_yy, k_xy = kernel(x, x), kernel(y, y), kernel(x, y)
    # a sample's kernel with itself is left out of the within-set means: including it is what biases the estimate
    within_real = (k_xx.sum() - np.trace(k_xx)) / (m * (m - 1))
    within_fake = (k_yy.sum() - np.trace(k_yy)) / (n * (n - 1))
    return float(within_real + within_fake - 2.0 * k_xy.mean())


def kid(
    real,
    fake,
    *,
    num_subsets: int = 100,
    subset_size: int = 1000,
    degree: int = 3,
    gamma: float | None = None,
    coef: float = 1.0,
    rng: np.random.Generator | int = 0,
) -> dict[str, float]:
    """Kernel Inception-style distance (Bińkowski et al. 2018): ``mmd2_unbiased`` with the polynomial kernel on
    ``num_subsets`` random subsets (each set drawn without replacement, size min(subset_size, n_real, n_fake));
    {"mean", "std" (ddof=0)} over the subsets."""
    x, y = _matrix(real, "kid real", 2), _matrix(fake, "kid fake", 2)
    if x.shape[1] != y.shape[1]:
        raise ValueError(f"kid: real and generated features differ in dimension: {x.shape[1]} vs {y.shape[1]}")
    kernel = partial(polynomial_kernel, degree=degree, gamma=1.0 / x.shape[1] if gamma is None else gamma, coef=coef)
    rng = np.random.default_rng(rng)
    size = min(subset_size, len(x), len(y))
    scores = []
    for _ in range(num_subsets):
        real_idx = rng.choice(len(x), size, replace=False)
        fake_idx = rng.choice(len(y), size, replace=False)
        scores.append(mmd2_unbiased(x[real_idx], y[fake_idx], kernel))
    return {"mean": float(np.mean(scores)), "std": float(np.std(scores))}


KID_OPTIONS = ("num_subsets", "subset_size", "degree", "gamma", "coef")  # what the KID metric passes on to kid


class KID(_RealVsGenerated):
    """KID: unbiased MMD² between real and generated features with k(x, y) = (gamma x·y + coef)^degree
    (gamma = 1/D by default), averaged over ``num_subsets`` seeded random subsets (``kid``).
    ``update(features, real)``; ``compute()`` -> {"mean": , "std": }."""

    higher_is_better = False

    def __init__(self, *, seed: int = 0, **kwargs):
        """``kwargs``: ``kid``'s options (KID_OPTIONS, with its defaults) and the Metric's own keywords."""
        options = {key: kwargs.pop(key) for key in KID_OPTIONS if key in kwargs}
        super().__init__(**kwargs)
        self.options, self.seed = options, seed

    def compute(self) -> dict[str, Tensor]:
        real, fake = self._both()
        scores = kid(real, fake, rng=np.random.default_rng(self.seed), **self.options)
        return {key: torch.tensor(v, dtype=torch.float64, device=self.device) for key, v in scores.items()}


# ---- precision and recall ---------------------------------------------------------------------------------------
def _knn_radii(x: np.ndarray, k: int) -> np.ndarray:
    # each row's sorted distances start with its own 0, so index k is the distance to its k-th nearest other sample
    chunks = [np.partition(_cdist(x[s : s + _CHUNK], x), k, axis=1)[:, k] for s in range(0, len(x), _CHUNK)]
    return np.concatenate(chunks)


def _fraction_inside(points: np.ndarray, centres: np.ndarray, radii: np.ndarray) -> float:
    """Fraction of points within (≤) the radius of at least one centre."""
    chunks = [(_cdist(points[s : s + _CHUNK], centres) <= radii).any(axis=1) for s in range(0, len(points), _CHUNK)]
    return float(np.concatenate(chunks).mean())


def knn_precision_recall(real, fake, k: int = 3) -> dict[str, float]:
    """Improved precision and recall (Kynkäänniemi et al. 2019). The real manifold is the union of balls around the
    real samples, each with radius = distance to its k-th nearest other real sample; precision = fraction of
    generated samples inside it. Recall = the same with the roles of real and generated swapped."""
    x, y = _matrix(real, "knn_precision_recall real", k + 1), _matrix(fake, "knn_precision_recall fake", k + 1)
    if x.shape[1] != y.shape[1]:
        raise ValueError(f"knn_precision_recall: feature dimensions differ: {x.shape[1]} vs {y.shape[1]}")
    return {
        "precision": _fraction_inside(y, x, _knn_radii(x, k)),
        "recall": _fraction_inside(x, y, _knn_radii(y, k)),
    }


class PrecisionRecall(_RealVsGenerated):
    """Improved precision/recall with k-NN manifolds (``knn_precision_recall``; k = 3 as in the paper).
    ``update(features, real)``; ``compute()`` -> {"precision": , "recall": }. Needs more than k samples per set."""

    higher_is_better = True

    def __init__(self, k: int = 3, **kwargs):
        super().__init__(**kwargs)
        if k < 1:
            raise ValueError(f"PrecisionRecall: k must be >= 1, got {k}")
        self.k = k

    def compute(self) -> dict[str, Tensor]:
        scores = knn_precision_recall(*self._both(), k=self.k)
        return {key: torch.tensor(v, dtype=torch.float64, device=self.device) for key, v in scores.items()}
