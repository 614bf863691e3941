"""Length-bucketed training batches: every clip once per epoch in batches of the batch size, far less padding than
random batches on the embedded data's real lengths, an order fixed by (seed, epoch) that a resume rebuilds, DDP
shares that Lightning's injected sampler selects, and the config switch."""

from __future__ import annotations

from collections import Counter

import numpy as np
import pytest
import torch
from hydra import compose, initialize_config_dir
from hydra.utils import instantiate
from lightning.fabric.utilities.data import _replace_dunder_methods, _set_sampler_epoch
from lightning.pytorch.trainer.states import RunningStage
from lightning.pytorch.utilities.data import _update_dataloader
from torch.utils.data import BatchSampler, DataLoader, DistributedSampler

from motiondiff.cli.common import REPO_DIR, register_resolvers
from motiondiff.data.bucketing import LengthBucketBatchSampler
from motiondiff.data.datamodules import PreparedDataModule, embedded_data_root
from motiondiff.data.datasets import MotionDataset, MotionRecord
from motiondiff.data.loaders import motion_loader
from motiondiff.data.resumable import EpochShuffleSampler, balance_weights

SYNTHETIC = np.random.default_rng(0).integers(40, 197, size=1000)  # HumanML3D-like lengths


def bucketed(lengths=SYNTHETIC, batch_size=64, seed=0, chunk_batches=4, sampler=None, weights=None, **kw):
    order = EpochShuffleSampler(len(lengths), seed, weights)
    return LengthBucketBatchSampler(sampler or order, batch_size, order=order, lengths=lengths,
                                    chunk_batches=chunk_batches, **kw)  # fmt: skip


def indices(batches) -> list[int]:
    return [i for b in batches for _, i in b]


def padding_fraction(batches, lengths) -> float:
    per = [lengths[np.asarray(b)] for b in batches]
    computed = sum(len(x) * x.max() for x in per)
    return float(1 - sum(x.sum() for x in per) / computed)


def test_every_clip_once_per_epoch_in_batches_of_the_batch_size():
    sampler = bucketed()
    sampler.sampler.set_epoch(3)
    batches = list(sampler)
    assert len(batches) == len(sampler) == 16  # 1000 = 15 x 64 + 40
    assert [len(b) for b in batches[:-1]] == [64] * 15 and len(batches[-1]) == 40
    assert sorted(indices(batches)) == list(range(1000))
    assert {e for b in batches for e, _ in b} == {3}  # keys for MotionDataset's per-(epoch, index) draws
    assert len(list(bucketed(drop_last=True))) == len(bucketed(drop_last=True)) == 15


@pytest.fixture(scope="module")
def embedded_lengths() -> dict[str, np.ndarray]:
    """Real clip lengths of the embedded train sets, as the shipped configs crop them."""
    mini = PreparedDataModule(embedded_data_root(), max_frames=80)
    composed = PreparedDataModule(embedded_data_root().parent / "bandai_mini_compositional", max_frames=196,
                                  extra_train=[embedded_data_root()])  # fmt: skip
    return {"bandai_mini": mini.dataset("train").item_lengths(0),
            "bandai_mini_compositional": composed.dataset("train").item_lengths(0)}  # fmt: skip


@pytest.mark.parametrize("name, at_most", [("bandai_mini", 0.35), ("bandai_mini_compositional", 0.15)])
def test_padding_is_far_below_random_batches_on_the_embedded_data(embedded_lengths, name, at_most):
    lengths = embedded_lengths[name]
    sampler = bucketed(lengths, batch_size=16, chunk_batches=64)
    random, grouped = [], []
    for epoch in range(5):
        order = sampler.order.order(epoch)
        random += [order[i : i + 16] for i in range(0, len(order), 16)]  # what the loader does without bucketing
        grouped += sampler.batches(epoch)
    assert padding_fraction(grouped, lengths) < at_most * padding_fraction(random, lengths)


def test_batches_are_fixed_by_seed_and_epoch_and_change_between_epochs():
    a, b = bucketed(seed=1), bucketed(seed=1)
    assert a.batches(2) == b.batches(2)
    assert a.batches(2) != a.batches(3) and a.batches(2) != bucketed(seed=2).batches(2)
    groups = [{frozenset(x) for x in a.batches(e)} for e in (2, 3)]
    assert len(groups[0] & groups[1]) == 0  # not only their order: which clips go together changes too


def test_a_resume_gives_the_rest_of_the_epoch_once():
    sampler = bucketed()
    sampler.sampler.set_epoch(5)
    full = list(sampler)
    sampler.sampler.set_epoch(0)  # Lightning sets the epoch again before iterating; the resume names it too
    sampler.resume(5, 6 * 64)
    assert list(sampler) == full[6:]
    assert list(sampler) == full  # the skip applies to one iteration only
    with pytest.raises(ValueError, match="whole number of batches"):
        sampler.resume(5, 100)


def _records(n: int = 40) -> list[MotionRecord]:
    rng = np.random.default_rng(0)
    return [MotionRecord(id=f"c{i}", motion=rng.normal(size=(int(rng.integers(20, 90)), 4)).astype(np.float32),
                         texts=["a", "b"]) for i in range(n)]  # fmt: skip


def test_item_lengths_are_the_lengths_the_items_get():
    ds = MotionDataset(_records(), np.zeros(4), np.ones(4), max_frames=64, unit_length=4, window_min_frames=24, seed=3)
    for epoch in (0, 1):
        assert ds.item_lengths(epoch).tolist() == [ds[(epoch, i)]["length"] for i in range(len(ds))]
    assert ds.item_lengths(0).tolist() != ds.item_lengths(1).tolist()  # random windows: new lengths each epoch
    fixed = MotionDataset(_records(), np.zeros(4), np.ones(4), max_frames=64, unit_length=4)
    assert fixed.item_lengths(0).tolist() == [min(len(r.motion), 64) // 4 * 4 for r in fixed.records]


def _epoch(loader, epoch: int) -> list[dict]:
    _set_sampler_epoch(loader, epoch)  # as Lightning does at every epoch start
    return list(loader)


def test_a_resumed_datamodule_loads_the_same_remaining_batches():
    """Through the datamodule (random window lengths, so the lengths bucketed are drawn per epoch): a resume at
    batch 3 of epoch 1 loads what the uninterrupted run loads from there, each batch padded to its longest clip."""

    def dm():
        module = PreparedDataModule(embedded_data_root(), batch_size=16, max_frames=80, window_min_frames=30,
                                    bucketing=True, bucket_chunk=4)  # fmt: skip
        module.setup("fit")
        return module

    full = _epoch(dm().train_dataloader(), 1)
    resumed = dm()
    resumed.resume_position = (1, 3 * 16)  # what motiondiff.lit.resume sets: (epoch, batches done x batch size)
    rest = _epoch(resumed.train_dataloader(), 1)
    assert len(rest) == len(full) - 3
    for a, b in zip(full[3:], rest, strict=True):
        assert a["id"] == b["id"] and a["text"] == b["text"]
        assert torch.equal(a["start"], b["start"]) and torch.equal(a["length"], b["length"])
        torch.testing.assert_close(a["motion"], b["motion"])
    assert all(b["motion"].shape[1] == int(b["length"].max()) for b in full)  # padded to the batch's own longest


def test_ddp_processes_share_each_step_and_run_the_same_number_of_steps():
    lengths = SYNTHETIC
    for world in (2, 3):
        ranks = [bucketed(sampler=DistributedSampler(range(1000), num_replicas=world, rank=r)) for r in range(world)]
        per_rank = [r.batches(4) for r in ranks]
        assert len({len(b) for b in per_rank}) == 1 and len(per_rank[0]) == len(ranks[0])
        assert sorted({i for b in per_rank for x in b for i in x}) == list(range(1000))
        full_steps = 1000 // (64 * world)
        for step in zip(*per_rank, strict=True):
            assert len({len(b) for b in step}) == 1  # the last step too, filled up with repeats
        for step in list(zip(*per_rank, strict=True))[:full_steps]:  # neighbouring lengths, rank r below rank r + 1
            for low, high in zip(step, step[1:], strict=False):
                assert lengths[low].max() <= lengths[high].min()
        seen = Counter(i for b in per_rank for x in b[:full_steps] for i in x)
        assert set(seen.values()) == {1}  # full steps share the clips out without repeats


def test_lightning_injects_its_distributed_sampler_and_keeps_order_and_resume():
    """Under DDP Lightning re-creates the batch sampler with a DistributedSampler in place of `sampler`: the copy
    takes that process's share of the same batches and keeps a resume set before."""
    ds = MotionDataset(_records(300), np.zeros(4), np.ones(4), max_frames=64, seed=0)
    # how Lightning calls train_dataloader(): recording the arguments and later attribute changes (the resume)
    with _replace_dunder_methods(DataLoader, "dataset"), _replace_dunder_methods(BatchSampler):
        loader = motion_loader(ds, 8, train=True, seed=5, bucketing=True, bucket_chunk=2, resume_position=(2, 16))
    injected = DistributedSampler(ds, num_replicas=2, rank=1, shuffle=False)
    ddp_loader = _update_dataloader(loader, injected, mode=RunningStage.TRAINING)
    copy = ddp_loader.batch_sampler
    assert isinstance(copy, LengthBucketBatchSampler) and (copy.num_replicas, copy.rank) == (2, 1)
    _set_sampler_epoch(ddp_loader, 2)
    assert copy.sampler is injected and injected.epoch == 2
    rank1 = DistributedSampler(ds, num_replicas=2, rank=1)
    expected = bucketed(ds.item_lengths(0), 8, seed=5, chunk_batches=2, sampler=rank1).batches(2)
    assert [[i for _, i in b] for b in copy] == expected[2:]  # the resume: 16 samples = 2 batches of this process
    assert [[i for _, i in b] for b in copy] == expected  # then whole epochs


def test_class_balanced_draws_are_bucketed_as_drawn():
    weights = balance_weights([0] * 900 + [1] * 100, 1.0)
    sampler = bucketed(weights=weights)
    assert Counter(indices([[(0, i) for i in b] for b in sampler.batches(0)])) == Counter(sampler.order.order(0))


def test_bad_arguments_are_refused():
    with pytest.raises(ValueError, match="one length per clip"):
        order = EpochShuffleSampler(1000)
        LengthBucketBatchSampler(order, 64, order=order, lengths=SYNTHETIC[:10]).batches(0)
    with pytest.raises(ValueError, match="batch_size and chunk_batches must be >= 1"):
        bucketed(batch_size=0)
    with pytest.raises(TypeError, match="order must be an EpochShuffleSampler"):
        LengthBucketBatchSampler(EpochShuffleSampler(10), 4, order=range(10), lengths=SYNTHETIC[:10])


@pytest.mark.parametrize(
    "dataset, on", [("humanml3d", True), ("bandai_mini_compositional", True), ("bandai_mini", False)]
)
def test_the_config_switch_reaches_the_train_loader(dataset, on):
    register_resolvers()
    with initialize_config_dir(config_dir=str(REPO_DIR / "conf"), version_base="1.3"):
        cfg = compose("train", overrides=[f"dataset={dataset}"])
    dm = instantiate(cfg.dataset.datamodule)
    assert dm.bucketing is on
    dm.datasets["train"] = MotionDataset(_records(), np.zeros(4), np.ones(4))  # no data needed to build the loader
    loader = dm.train_dataloader()
    assert isinstance(loader.batch_sampler, LengthBucketBatchSampler) is on
