"""How much of a training batch is padding, with and without length bucketing: counted from clip lengths alone.

The denoiser computes every frame of a batch padded to its longest clip, so the share of computed frames that are
real is what bucketing buys (`motiondiff.data.bucketing`). Attention costs the square of the padded length; its real
share is reported too. No model runs: the numbers come from the batches the training samplers would make.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from motiondiff.data.bucketing import LengthBucketBatchSampler
from motiondiff.data.resumable import EpochShuffleSampler


def padding_stats(batches: Sequence[Sequence[int]], lengths: np.ndarray) -> dict:
    """Per batch of clip indices: real frames, frames computed when padded to the batch's longest clip, and their
    ratios (frames, and frames² for attention)."""
    lengths = np.asarray(lengths)
    if not len(batches) or any(not len(b) for b in batches):
        raise ValueError("padding_stats needs at least one batch and no empty batch")
    per = [lengths[np.asarray(b)] for b in batches]
    real = sum(int(x.sum()) for x in per)
    computed = sum(len(x) * int(x.max()) for x in per)
    real_sq = sum(int((x.astype(np.int64) ** 2).sum()) for x in per)
    computed_sq = sum(len(x) * int(x.max()) ** 2 for x in per)
    return {
        "batches": len(per),
        "real_frames": real,
        "computed_frames": computed,
        "padded_frames_per_batch": (computed - real) / len(per),
        "padding_fraction": (computed - real) / computed,
        "real_over_computed": real / computed,
        "attention_real_over_computed": real_sq / computed_sq,
    }


def compare_batching(lengths: np.ndarray, batch_size: int, chunk_batches: int = 64, seed: int = 0,
                     epochs: int = 3) -> dict:  # fmt: skip
    """Padding of the training batches of ``epochs`` epochs: ``random`` (the plain epoch order cut into batches, as
    the loader does without bucketing) and ``bucketed`` (`LengthBucketBatchSampler`), for clips of ``lengths``."""
    lengths = np.asarray(lengths)
    order = EpochShuffleSampler(len(lengths), seed)
    bucketed = LengthBucketBatchSampler(order, batch_size, order=order, lengths=lengths, chunk_batches=chunk_batches)
    plain, grouped = [], []
    for epoch in range(epochs):
        keys = order.order(epoch)
        plain += [keys[i : i + batch_size] for i in range(0, len(keys), batch_size)]
        grouped += bucketed.batches(epoch)
    return {
        "clips": len(lengths),
        "batch_size": batch_size,
        "chunk_batches": chunk_batches,
        "epochs": epochs,
        "length_min_mean_max": [int(lengths.min()), float(lengths.mean()), int(lengths.max())],
        "random": padding_stats(plain, lengths),
        "bucketed": padding_stats(grouped, lengths),
    }


def markdown(result: dict) -> str:
    """The comparison as a Markdown table."""
    low, mean, high = result["length_min_mean_max"]
    rows = [f"{result['clips']} clips of {low}-{high} frames (mean {mean:.1f}), batch size {result['batch_size']}, "
            f"sorting chunks of {result['chunk_batches']} batches, {result['epochs']} epochs", "",
            "| batching | padded frames / batch | real / computed frames | real / computed attention |",
            "|---|---|---|---|"]  # fmt: skip
    for name in ("random", "bucketed"):
        s = result[name]
        rows.append(f"| {name} | {s['padded_frames_per_batch']:.0f} | {s['real_over_computed']:.3f} | "
                    f"{s['attention_real_over_computed']:.3f} |")  # fmt: skip
    return "\n".join(rows)
