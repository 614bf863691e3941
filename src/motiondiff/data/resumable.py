"""Training order that can be rebuilt at any step, so a killed run resumes exactly where its checkpoint was.

A RandomSampler draws each epoch's order from a generator that has moved on by the time a checkpoint is written,
and a dataset-wide crop generator has already served the batches the loader prefetched; neither can be rewound.
Here the order of an epoch is a function of (seed, epoch) alone, and the sampler yields (epoch, index) keys so the
dataset draws each item's random window and caption from (seed, epoch, index) alone (`MotionDataset.__getitem__`).
A resume only has to say which epoch and how many of its samples were used (`resume`).
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import torch
from torch.utils.data import Sampler


def mixed_seed(*parts: int) -> int:
    """One 63-bit seed from several integers (numpy's SeedSequence mixes them, so nearby inputs give unrelated seeds)."""
    return int(np.random.SeedSequence([int(p) for p in parts]).generate_state(2, np.uint64)[0] >> np.uint64(1))


class EpochShuffleSampler(Sampler[tuple[int, int]]):
    """Each epoch: a permutation of the clips, or with ``weights`` as many draws with replacement in proportion to
    them (class-balanced training, `balance_weights`); either way a function of (seed, epoch) alone."""

    def __init__(self, size: int, seed: int = 0, weights: np.ndarray | None = None):
        self.size, self.seed = int(size), int(seed)
        if weights is not None:
            weights = np.asarray(weights, dtype=np.float64)
            if (
                weights.shape != (self.size,)
                or not np.all(np.isfinite(weights))
                or weights.min() < 0
                or weights.sum() <= 0
            ):
                raise ValueError(f"sampling weights must be {self.size} finite non-negative numbers, not all zero")
        self.weights = None if weights is None else torch.from_numpy(weights)
        self.epoch = 0
        self._skip = 0

    def set_epoch(self, epoch: int) -> None:
        """Lightning calls this at every epoch start."""
        self.epoch = int(epoch)

    def resume(self, epoch: int, samples_done: int) -> None:
        """The next iteration is epoch ``epoch`` without its first ``samples_done`` samples."""
        self.epoch, self._skip = int(epoch), int(samples_done)

    def order(self, epoch: int) -> list[int]:
        generator = torch.Generator().manual_seed(mixed_seed(self.seed, epoch))
        if self.weights is not None:
            return torch.multinomial(self.weights, self.size, replacement=True, generator=generator).tolist()
        return torch.randperm(self.size, generator=generator).tolist()

    def __iter__(self) -> Iterator[tuple[int, int]]:
        epoch, skip, self._skip = self.epoch, self._skip, 0
        for index in self.order(epoch)[skip:]:
            yield (epoch, index)

    def __len__(self) -> int:
        return self.size


def balance_weights(labels: list[int] | np.ndarray, power: float) -> np.ndarray | None:
    """Per-clip sampling weights count(label)^-power: 0 keeps the data's own frequencies (None), 1 makes every
    label equally likely, 0.5 is in between (rare labels drawn more often without being repeated as much as at 1).
    Clips without a label (negative ids) count as one group."""
    if not power:
        return None
    if power < 0:
        raise ValueError(f"balance must be >= 0 (0: off, 1: every label equally often), got {power}")
    labels = np.asarray(labels)
    keys = np.where(labels < 0, -1, labels)
    _, inverse, counts = np.unique(keys, return_inverse=True, return_counts=True)
    return counts[inverse].astype(np.float64) ** -float(power)
