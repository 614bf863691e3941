"""Motion-generation metrics as torchmetrics `Metric`s, so an evaluation run under DDP syncs its states.

Each metric's math lives once in a plain float64 function (numpy in, Python float or dict out) that the `Metric`'s
``compute()`` calls; the `Metric` only accumulates inputs in states registered with ``add_state`` (``"cat"`` for
per-sample features, ``"sum"`` for running totals), so every process computes the same value after the sync.
Random draws (Diversity, MultiModality, KID subsets) use ``np.random.default_rng(seed)`` afresh in each
``compute()``, so a metric's value is a function of its inputs.

Protocols
---------
Text-to-motion (Guo et al. 2022, "Generating diverse and natural 3D human motions from text"; MDM appendix B).
Features are the text-motion matching evaluator's embeddings (`motiondiff.eval.evaluators`):

- FID: Fréchet distance between Gaussians fitted to real and generated motion embeddings.
- R-Precision: the evaluation batches of 32 are the pools: for each caption, its own motion and the 31 other
  motions of its batch are ranked by Euclidean distance; top-1/2/3 accuracy (chance = k/32). This is the official
  code's direction (the papers' wording, captions ranked per motion, is the transposed matrix and in general gives
  slightly different numbers).
- MM Dist: mean Euclidean distance between each generated motion and its caption.
- Diversity: mean distance between 300 random pairs of generated motions.
- MultiModality: 30 generations of each of 100 captions, mean distance of 10 random pairs per caption.

Small deliberate differences from the official code: Diversity takes min(300, N) pairs where the official code
requires N > 300; MultiModality draws its pairs per condition where the official code draws one set of repeat
indices for all conditions (the same expectation); MM Dist averages over all pairs, where the official code only
sees the pairs of full batches of 32.

Action-to-motion (Guo et al. 2020, HumanAct12 / UESTC; MDM section 4.2): features are the action classifier's
penultimate activations; FID, classifier accuracy, Diversity (200 pairs) and MultiModality (20 pairs per action).

Unconstrained (MoDi, Raab et al. 2023; vvMDM; MDM table 4): FID, KID, improved precision/recall (Kynkäänniemi et al.
2019) on evaluator features, Diversity, and vvMDM's Smoothness on the motion itself.

Every metric is computed over several replications and reported as mean ± 95% CI (`motiondiff.eval.report`).
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial

import numpy as np
import scipy.linalg
import torch
from torch import Tensor
from torchmetrics import Metric
from torchmetrics.classification import MulticlassAccuracy
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


class _RealVsGenerated(Metric):
    """Accumulates features of real and of generated samples in two "cat" states."""

    full_state_update = False
    is_differentiable = False

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.add_state("real_features", [], dist_reduce_fx="cat")
        self.add_state("fake_features", [], dist_reduce_fx="cat")

    def update(self, features: Tensor, real: bool) -> None:
        """features [N, D]: of real samples when ``real`` is true, of generated ones otherwise."""
        features = _check_features(features, type(self).__name__)
        (self.real_features if real else self.fake_features).append(features)

    def _both(self) -> tuple[Tensor, Tensor]:
        name = type(self).__name__
        return _gathered(self.real_features, f"{name} real"), _gathered(self.fake_features, f"{name} generated")


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


class _TextMotionPairs(Metric):
    """Accumulates matched (text, motion) embedding pairs in order, in two "cat" states."""

    full_state_update = False
    is_differentiable = False

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.add_state("text", [], dist_reduce_fx="cat")
        self.add_state("motion", [], dist_reduce_fx="cat")

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

    def _both(self) -> tuple[Tensor, Tensor]:
        name = type(self).__name__
        return _gathered(self.text, f"{name} text"), _gathered(self.motion, f"{name} motion")


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


class KID(_RealVsGenerated):
    """KID: unbiased MMD² between real and generated features with k(x, y) = (gamma x·y + coef)^degree
    (gamma = 1/D by default), averaged over ``num_subsets`` seeded random subsets (``kid``).
    ``update(features, real)``; ``compute()`` -> {"mean": , "std": }."""

    higher_is_better = False

    def __init__(
        self,
        num_subsets: int = 100,
        subset_size: int = 1000,
        degree: int = 3,
        gamma: float | None = None,
        coef: float = 1.0,
        seed: int = 0,
        **kwargs,
    ):
        super().__init__(**kwargs)
        self.num_subsets, self.subset_size, self.seed = num_subsets, subset_size, seed
        self.degree, self.gamma, self.coef = degree, gamma, coef

    def compute(self) -> dict[str, Tensor]:
        real, fake = self._both()
        scores = kid(
            real,
            fake,
            num_subsets=self.num_subsets,
            subset_size=self.subset_size,
            degree=self.degree,
            gamma=self.gamma,
            coef=self.coef,
            rng=np.random.default_rng(self.seed),
        )
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
