"""The project's distribution and retrieval metrics (motiondiff.metrics: numpy/scipy inside torchmetrics `Metric`s)
against torchmetrics' own: FID (FrechetInceptionDistance with the features passed straight through), KID
(KernelInceptionDistance's estimator on the same subsets) and R-precision (RetrievalHitRate per caption); and k-NN
precision/recall, which torchmetrics lacks, against the `prdc` package.

    /tmp/depvenv/bin/python bench/dependencies/metrics.py

Features: 512-d (the text-motion evaluator's size), correlated, real and generated sets that differ in mean and
covariance; one set with more samples than dimensions (2000), one with fewer (300, singular covariances, where
FID's matrix square root needs care) and one far from the origin (every feature + 100). torchmetrics is already a dependency (the project's metrics are its
`Metric`s), so size is not a question there: this is about faithfulness and speed (prdc's size is recorded). Writes
docs/results/dependencies/metrics.json.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import torch

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import install_cost, require, speed, write  # noqa: E402
from torchmetrics.functional.retrieval import retrieval_hit_rate  # noqa: E402
from torchmetrics.image.fid import FrechetInceptionDistance  # noqa: E402
from torchmetrics.image.kid import poly_mmd  # noqa: E402

from motiondiff.metrics.distribution import FID, knn_precision_recall, mmd2_unbiased, polynomial_kernel  # noqa: E402
from motiondiff.metrics.text_motion import r_precision  # noqa: E402

DIM = 512


class PassThrough(torch.nn.Module):
    """Features in, features out: lets torchmetrics' image metrics take precomputed features."""

    num_features = DIM

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return x


def feature_sets(n: int, seed: int = 0, offset: float = 0.0) -> tuple[torch.Tensor, torch.Tensor]:
    """Correlated real and generated features; `offset` is added to every feature (a large one tests the
    covariance torchmetrics forms from running sums, sum x x^T - n mu mu^T, for cancellation)."""
    rng = np.random.default_rng(seed)
    mix = rng.normal(size=(DIM, DIM)) / np.sqrt(DIM)
    real = rng.normal(size=(n, DIM)) @ mix + offset
    fake = (rng.normal(size=(n, DIM)) * 1.1 + 0.2) @ (mix + 0.05 * rng.normal(size=(DIM, DIM)) / np.sqrt(DIM)) + offset
    return torch.tensor(real, dtype=torch.float32), torch.tensor(fake, dtype=torch.float32)


def fid_row(real: torch.Tensor, fake: torch.Tensor) -> dict:
    def ours():
        metric = FID()
        metric.update(real, real=True)
        metric.update(fake, real=False)
        return float(metric.compute())

    def theirs(features_dtype=torch.float32):
        def run():
            metric = FrechetInceptionDistance(feature=PassThrough())
            metric.update(real.to(features_dtype), real=True)
            metric.update(fake.to(features_dtype), real=False)
            return float(metric.compute())

        return run

    a, b, b64 = ours(), theirs()(), theirs(torch.float64)()
    return {"project": a, "torchmetrics": b, "torchmetrics_float64_features": b64,
            "relative_difference": abs(a - b) / abs(a), "relative_difference_float64_features": abs(a - b64) / abs(a),
            **speed(ours, theirs(), repeats=3)}  # fmt: skip


def kid_row(real: torch.Tensor, fake: torch.Tensor, subsets: int = 20, size: int = 200) -> dict:
    rng = np.random.default_rng(0)
    picks = [(rng.choice(len(real), size, replace=False), rng.choice(len(fake), size, replace=False))
             for _ in range(subsets)]  # fmt: skip
    r64, f64 = real.double().numpy(), fake.double().numpy()

    def ours():
        return [mmd2_unbiased(r64[i], f64[j], polynomial_kernel) for i, j in picks]

    def theirs():
        return [float(poly_mmd(real.double()[i], fake.double()[j])) for i, j in picks]

    a, b = np.array(ours()), np.array(theirs())
    return {"max_relative_difference_per_subset": float(np.max(np.abs(a - b) / np.abs(a))), **speed(ours, theirs)}


def precision_recall_row(real: torch.Tensor, fake: torch.Tensor, k: int = 3) -> dict:
    """The project's k-NN precision/recall against the `prdc` package (Naeem et al. 2020, the same two measures plus
    density and coverage; it prints a line per call, silenced here)."""
    import contextlib
    import io

    prdc = require("prdc")
    r, f = real.double().numpy(), fake.double().numpy()

    def ours():
        return knn_precision_recall(r, f, k=k)

    def theirs():
        with contextlib.redirect_stdout(io.StringIO()):
            out = prdc.compute_prdc(r, f, nearest_k=k)
        return {"precision": float(out["precision"]), "recall": float(out["recall"])}

    a, b = ours(), theirs()
    # ties: every real sample four times (its 3rd neighbour is itself, radius 0) and the same set as generated: all
    # generated samples lie on real ones, so precision and recall are 1 with "within or on the radius"
    dup = np.repeat(r[:200], 4, axis=0)
    with contextlib.redirect_stdout(io.StringIO()):
        tie_prdc = prdc.compute_prdc(dup, dup.copy(), nearest_k=k)
    return {"project": a, "prdc": b, "max_abs_difference": max(abs(a[key] - b[key]) for key in a),
            "duplicated_samples": {"project": knn_precision_recall(dup, dup.copy(), k=k),
                                   "prdc": {"precision": float(tie_prdc["precision"]),
                                            "recall": float(tie_prdc["recall"])}},
            **speed(ours, theirs, repeats=3)}  # fmt: skip


def r_precision_row(n: int = 1024, pool: int = 32, seed: int = 1) -> dict:
    rng = np.random.default_rng(seed)
    text = rng.normal(size=(n, DIM))
    motion = 0.08 * text + rng.normal(size=(n, DIM))  # weakly matched: top-1 about 0.3, as real evaluators

    def ours():
        return r_precision(text, motion, top_k=3, pool_size=pool)

    def theirs():
        out = {f"top{k}": [] for k in (1, 2, 3)}
        for s in range(0, n - n % pool, pool):
            t, m = torch.tensor(text[s : s + pool]), torch.tensor(motion[s : s + pool])
            dist = torch.cdist(t, m)
            for i in range(pool):
                target = torch.arange(pool) == i
                for k in (1, 2, 3):
                    out[f"top{k}"].append(float(retrieval_hit_rate(-dist[i], target, top_k=k)))
        return {key: float(np.mean(v)) for key, v in out.items()}

    a, b = ours(), theirs()
    return {"project": a, "torchmetrics": b, "max_abs_difference": max(abs(a[k] - b[k]) for k in a),
            **speed(ours, theirs, repeats=3)}  # fmt: skip


def main() -> int:
    result = {"features": DIM}
    for name, n, offset in (("fid_2000_samples", 2000, 0.0), ("fid_300_samples", 300, 0.0),
                            ("fid_2000_samples_offset_100", 2000, 100.0)):  # fmt: skip
        result[name] = fid_row(*feature_sets(n, offset=offset))
    real, fake = feature_sets(2000)
    result["kid_estimator_20_subsets_of_200"] = kid_row(real, fake)
    result["precision_recall_k3"] = precision_recall_row(real, fake)
    result["r_precision_top3_pools_of_32"] = r_precision_row()
    result["size"] = {"prdc": install_cost("prdc")}
    write("metrics", result)
    print(result)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
