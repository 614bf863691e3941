"""Length-bucketed training batches: each batch holds clips of similar length, so little of it is padding.

The collate pads a batch to its longest clip and the denoiser computes every padded frame like a real one, so a
random batch of clips of 40-196 frames is mostly padding. Here an epoch's order (`EpochShuffleSampler`: a function
of (seed, epoch) alone) is cut into chunks of ``chunk_batches`` batches, each chunk is sorted by length (ties keep
their random order) and cut into batches, and the full batches are shuffled; the one partial batch, if any, comes
last. Batches stay random across the epoch and across epochs, and resumable: the batches of an epoch depend on
(seed, epoch) alone, so a resume only skips the ones already used. On a dataset smaller than a chunk the batches are
the whole epoch sorted: their composition then varies little between epochs (ties and random window lengths only).

DDP: Lightning puts a ``DistributedSampler`` in place of ``sampler`` (it re-creates the batch sampler with it); its
``num_replicas`` and ``rank`` say which share this process takes. Each training step takes ``num_replicas`` batches
of neighbouring lengths, one per process, so no process waits for a much longer batch than its own; a short last
step is filled up with repeats of its own clips, so every process runs the same number of steps.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator

import numpy as np
from torch.utils.data import BatchSampler, DistributedSampler, Sampler

from motiondiff.data.resumable import EpochShuffleSampler, mixed_seed

Lengths = np.ndarray | Callable[[int], np.ndarray]
_BATCH_SHUFFLE = 1  # mixed into the seed of the batch order, so it is not the generator of the clip order


class LengthBucketBatchSampler(BatchSampler):
    """Batches of (epoch, index) keys for `MotionDataset`, grouped by length.

    ``order``: the epoch's clip order (its seed and class-balance weights). ``sampler``: what Lightning sets the epoch
    on, ``order`` itself, or under DDP the ``DistributedSampler`` Lightning injects (see the module docstring).
    ``lengths``: every clip's frames, or a function epoch -> them (random training windows: `MotionDataset.item_lengths`).
    ``chunk_batches``: batches sorted together; more pads less, fewer keeps batch composition more random.
    """

    def __init__(
        self,
        sampler: Sampler,
        batch_size: int,
        drop_last: bool = False,
        *,
        order: EpochShuffleSampler,
        lengths: Lengths,
        chunk_batches: int = 64,
    ):
        if int(batch_size) < 1 or int(chunk_batches) < 1:
            raise ValueError(f"batch_size and chunk_batches must be >= 1, got {batch_size} and {chunk_batches}")
        if not isinstance(order, EpochShuffleSampler):
            raise TypeError(f"order must be an EpochShuffleSampler (the resumable epoch order), got {type(order)}")
        if not hasattr(sampler, "epoch"):
            raise TypeError(f"sampler must carry the epoch (`order` or a DistributedSampler), got {type(sampler)}")
        self.sampler, self.order, self.lengths = sampler, order, lengths
        self.batch_size, self.drop_last, self.chunk_batches = int(batch_size), bool(drop_last), int(chunk_batches)
        distributed = isinstance(sampler, DistributedSampler)
        self.num_replicas, self.rank = (sampler.num_replicas, sampler.rank) if distributed else (1, 0)
        self._skip = 0

    def resume(self, epoch: int, samples_done: int) -> None:
        """The next iteration is epoch ``epoch`` without the batches of its first ``samples_done`` samples (this
        process's; a whole number of batches, as `motiondiff.lit.resume` saves them)."""
        if samples_done % self.batch_size:
            raise ValueError(f"resume at {samples_done} samples is not a whole number of batches of {self.batch_size}: "
                             "resume with the batch_size the checkpoint was trained with")  # fmt: skip
        self.sampler.set_epoch(int(epoch))
        self._skip = int(samples_done) // self.batch_size

    def _lengths(self, epoch: int) -> np.ndarray:
        lengths = np.asarray(self.lengths(epoch) if callable(self.lengths) else self.lengths)
        if lengths.shape != (self.order.size,):
            raise ValueError(f"lengths must give one length per clip ({self.order.size}), got shape {lengths.shape}")
        return lengths

    def steps(self, epoch: int) -> list[np.ndarray]:
        """The epoch's training steps, each the clip indices of all processes' batches (shortest first)."""
        keys = np.asarray(self.order.order(epoch), dtype=np.int64)
        lengths = self._lengths(epoch)[keys]
        step = self.batch_size * self.num_replicas
        chunk = step * self.chunk_batches
        parts = [
            keys[s : s + chunk][np.argsort(lengths[s : s + chunk], kind="stable")] for s in range(0, len(keys), chunk)
        ]
        ordered = np.concatenate(parts) if parts else keys
        full = len(ordered) // step
        steps = [ordered[i * step : (i + 1) * step] for i in range(full)]
        rng = np.random.default_rng(mixed_seed(self.order.seed, epoch, _BATCH_SHUFFLE))
        steps = [steps[i] for i in rng.permutation(full)]
        tail = ordered[full * step :]
        if len(tail) and not self.drop_last:  # fill up to a share per process with repeats of its own clips
            steps.append(np.resize(tail, math.ceil(len(tail) / self.num_replicas) * self.num_replicas))
        return steps

    def batches(self, epoch: int) -> list[list[int]]:
        """This process's batches of ``epoch`` (clip indices), the whole epoch."""
        out = []
        for step in self.steps(epoch):
            share = len(step) // self.num_replicas
            out.append(step[self.rank * share : (self.rank + 1) * share].tolist())
        return out

    def __iter__(self) -> Iterator[list[tuple[int, int]]]:
        epoch, skip, self._skip = int(self.sampler.epoch), self._skip, 0
        for batch in self.batches(epoch)[skip:]:
            yield [(epoch, index) for index in batch]

    def __len__(self) -> int:
        step = self.batch_size * self.num_replicas
        return self.order.size // step if self.drop_last else math.ceil(self.order.size / step)
