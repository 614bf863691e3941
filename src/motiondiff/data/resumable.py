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
    def __init__(self, size: int, seed: int = 0):
        self.size, self.seed = int(size), int(seed)
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
        return torch.randperm(self.size, generator=generator).tolist()

    def __iter__(self) -> Iterator[tuple[int, int]]:
        epoch, skip, self._skip = self.epoch, self._skip, 0
        for index in self.order(epoch)[skip:]:
            yield (epoch, index)

    def __len__(self) -> int:
        return self.size
