"""Motion-generation metrics as torchmetrics `Metric`s, so an evaluation run under DDP syncs its states.

Each metric's math lives once in a plain float64 function (numpy in, Python float or dict out) that the `Metric`'s
``compute()`` calls; the `Metric` only accumulates inputs in states registered with ``add_state`` (``"cat"`` for
per-sample features, ``"sum"`` for running totals), so every process computes the same value after the sync.
Random draws (Diversity, MultiModality, KID subsets) use ``np.random.default_rng(seed)`` afresh in each
``compute()``, so a metric's value is a function of its inputs.

Protocols
---------
Text-to-motion (Guo et al. 2022, "Generating diverse and natural 3D human motions from text"; MDM appendix B).
Features are the text-motion matching evaluator's embeddings (`motiondiff.models.evaluators.networks`):

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

from motiondiff.metrics.distribution import (
    FID,
    KID,
    PrecisionRecall,
    frechet_distance,
    gaussian_statistics,
    kid,
    knn_precision_recall,
    mmd2_unbiased,
    polynomial_kernel,
)
from motiondiff.metrics.spread import (
    ActionAccuracy,
    Diversity,
    MultiModality,
    Smoothness,
    diversity,
    multimodality,
    smoothness,
)
from motiondiff.metrics.text_motion import MMDist, RPrecision, mm_dist, r_precision, r_precision_counts

__all__ = ["FID", "KID", "PrecisionRecall", "frechet_distance", "gaussian_statistics", "kid", "knn_precision_recall",
           "mmd2_unbiased", "polynomial_kernel", "ActionAccuracy", "Diversity", "MultiModality", "Smoothness",
           "diversity", "multimodality", "smoothness", "MMDist", "RPrecision", "mm_dist", "r_precision",
           "r_precision_counts"]  # fmt: skip
