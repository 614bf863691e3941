"""The DataLoader of a split: a resumable training order (plain or length-bucketed), repeatable worker seeds.

Training batches come in an order a resumed run can rebuild (`motiondiff.data.resumable`): clip by clip from an
`EpochShuffleSampler`, or with ``bucketing`` in batches of similar-length clips (`motiondiff.data.bucketing`), which
pads far less where clip lengths vary. Evaluation loaders keep the dataset's order. Every batch is padded to its own
longest clip (`collate_motion`).
"""

from __future__ import annotations

import numpy as np
import torch
from torch.utils.data import DataLoader, get_worker_info

from motiondiff.data.bucketing import LengthBucketBatchSampler
from motiondiff.data.datasets import MotionDataset, collate_motion
from motiondiff.data.resumable import EpochShuffleSampler, balance_weights


def _reseed_worker(worker_id: int) -> None:
    # Each worker gets a copy of the dataset's rng: without this all workers draw the same crops/captions.
    info = get_worker_info()
    if info is not None and isinstance(info.dataset, MotionDataset):
        info.dataset.rng = np.random.default_rng(info.seed)


def motion_loader(
    dataset: MotionDataset,
    batch_size: int,
    *,
    train: bool,
    seed: int = 0,
    num_workers: int = 0,
    balance: float = 0.0,
    bucketing: bool = False,
    bucket_chunk: int = 64,
    resume_position: tuple[int, int] | None = None,
) -> DataLoader:
    """A loader of ``dataset``. ``train``: the resumable order (class-balanced with ``balance``, length-bucketed with
    ``bucketing``, sorted in chunks of ``bucket_chunk`` batches), started at ``resume_position`` = (epoch, samples
    already used in it) when a run resumes; otherwise the dataset's order."""
    batching: dict = {"batch_size": batch_size, "drop_last": False}
    if train:
        order = EpochShuffleSampler(len(dataset), seed, balance_weights([r.action for r in dataset.records], balance))
        if bucketing:
            sampler = LengthBucketBatchSampler(order, batch_size, order=order, lengths=dataset.item_lengths,
                                               chunk_batches=bucket_chunk)  # fmt: skip
            batching = {"batch_sampler": sampler}
        else:
            sampler = order
            batching["sampler"] = sampler
        if resume_position is not None:
            sampler.resume(*resume_position)
    return DataLoader(
        dataset,
        **batching,
        num_workers=num_workers,
        persistent_workers=num_workers > 0,
        collate_fn=collate_motion,
        worker_init_fn=_reseed_worker,
        generator=torch.Generator().manual_seed(seed),  # repeatable worker seeds
    )
