"""Lightning datamodules: one base that turns `load_split` output into loaders, one subclass per dataset.

Every datamodule yields the same batch (see `collate_motion`): motion [B,N,D] float32 (normalised),
mask [B,N] bool, length [B], text list[str], action [B] long, id list[str].
"""

from __future__ import annotations

import abc
import logging
from pathlib import Path

import lightning as L
import numpy as np
import torch
from torch.utils.data import DataLoader, get_worker_info

from motiondiff.data.datasets import MotionDataset, MotionRecord, collate_motion
from motiondiff.data.humanml3d import HUMANML3D, KIT, OfficialLayout, load_official_split
from motiondiff.data.prepared import load_split as load_prepared_split

log = logging.getLogger(__name__)

SplitData = tuple[list[MotionRecord], np.ndarray, np.ndarray]
_STAGE_SPLITS = {"fit": ("train", "val"), "validate": ("val",), "test": ("test",), "predict": ("test",)}


def _reseed_worker(worker_id: int) -> None:
    # Each worker gets a copy of the dataset's rng: without this all workers draw the same crops/captions.
    info = get_worker_info()
    if info is not None and isinstance(info.dataset, MotionDataset):
        info.dataset.rng = np.random.default_rng(info.seed)


class MotionDataModule(L.LightningDataModule, abc.ABC):
    """Base: subclasses only say how to read a split (`load_split`) and the skeleton facts.

    `load_split` must return the training-set statistics for every split (the official layouts ship one
    Mean/Std); val/test are normalised with them, and a split that returns different statistics is an error.
    """

    def __init__(
        self,
        batch_size: int = 64,
        num_workers: int = 0,
        max_frames: int = 196,
        unit_length: int = 4,
        seed: int = 0,
    ):
        super().__init__()
        self.batch_size = batch_size
        self.num_workers = num_workers
        self.max_frames = max_frames
        self.unit_length = unit_length
        self.seed = seed
        self.datasets: dict[str, MotionDataset] = {}
        self._mean: np.ndarray | None = None
        self._std: np.ndarray | None = None

    @abc.abstractmethod
    def load_split(self, split: str) -> SplitData:
        """(records, mean, std) of `split` ('train', 'val' or 'test'); motions not normalised."""

    @property
    @abc.abstractmethod
    def num_joints(self) -> int: ...

    @property
    @abc.abstractmethod
    def fps(self) -> float: ...

    @property
    def feature_dim(self) -> int:
        return int(self.mean.shape[0])

    def _stats(self) -> tuple[np.ndarray, np.ndarray]:
        if self._mean is None or self._std is None:
            raise RuntimeError(f"{type(self).__name__}: call setup() before reading mean/std")
        return self._mean, self._std

    @property
    def mean(self) -> np.ndarray:
        return self._stats()[0]

    @property
    def std(self) -> np.ndarray:
        return self._stats()[1]

    def _set_stats(self, split: str, mean: np.ndarray, std: np.ndarray) -> None:
        if self._mean is None:
            self._mean, self._std = mean, std
        elif not (np.array_equal(self._mean, mean) and np.array_equal(self._std, std)):
            raise ValueError(f"{type(self).__name__}: split {split!r} returned other Mean/Std than the first")

    def dataset(self, split: str) -> MotionDataset:
        """The MotionDataset of a split, loaded once."""
        if split not in self.datasets:
            records, mean, std = self.load_split(split)
            self._set_stats(split, mean, std)
            self.datasets[split] = MotionDataset(
                records,
                mean,
                std,
                max_frames=self.max_frames,
                unit_length=self.unit_length,
                train=split == "train",
                seed=self.seed,
            )
        return self.datasets[split]

    def setup(self, stage: str | None = None) -> None:
        splits = _STAGE_SPLITS.get(stage or "", ("train", "val", "test"))  # None: every split
        for split in splits:
            self.dataset(split)

    def _loader(self, split: str) -> DataLoader:
        train = split == "train"
        return DataLoader(
            self.dataset(split),
            batch_size=self.batch_size,
            shuffle=train,
            drop_last=False,
            num_workers=self.num_workers,
            persistent_workers=self.num_workers > 0,
            collate_fn=collate_motion,
            worker_init_fn=_reseed_worker,
            generator=torch.Generator().manual_seed(self.seed),  # repeatable shuffling and worker seeds
        )

    def train_dataloader(self) -> DataLoader:
        return self._loader("train")

    def val_dataloader(self) -> DataLoader:
        return self._loader("val")

    def test_dataloader(self) -> DataLoader:
        return self._loader("test")

    def predict_dataloader(self) -> DataLoader:
        return self._loader("test")


class OfficialLayoutDataModule(MotionDataModule):
    """A root in the official HumanML3D/KIT-ML layout (see `motiondiff.data.humanml3d`)."""

    layout: OfficialLayout

    def __init__(
        self,
        root: str | Path,
        batch_size: int = 64,
        num_workers: int = 0,
        max_frames: int | None = None,
        unit_length: int | None = None,
        seed: int = 0,
    ):
        super().__init__(
            batch_size=batch_size,
            num_workers=num_workers,
            max_frames=self.layout.max_motion_len if max_frames is None else max_frames,
            unit_length=self.layout.unit_length if unit_length is None else unit_length,
            seed=seed,
        )
        self.root = Path(root)

    def load_split(self, split: str) -> SplitData:
        return load_official_split(self.root, split, dataset=self.layout.key)

    @property
    def feature_dim(self) -> int:
        return self.layout.feature_dim  # known before setup(): models are built from it

    @property
    def num_joints(self) -> int:
        return self.layout.num_joints

    @property
    def fps(self) -> float:
        return self.layout.fps


class HumanML3DDataModule(OfficialLayoutDataModule):
    layout = HUMANML3D


class KITDataModule(OfficialLayoutDataModule):
    layout = KIT


class PreparedDataModule(MotionDataModule):
    """A folder written by `python -m motiondiff.data.prepare` (Bandai, the embedded bandai_mini, BVH folders).

    Clips shorter than `min_frames` are left out of training and evaluation (logged with their count); the
    captions are GENERATED ones (see motiondiff.data.captions) and each record says so in its meta.
    """

    def __init__(
        self,
        root: str | Path,
        batch_size: int = 64,
        num_workers: int = 0,
        max_frames: int = 196,
        min_frames: int = 16,
        unit_length: int = 1,
        seed: int = 0,
    ):
        super().__init__(batch_size, num_workers, max_frames, unit_length, seed)
        self.root = Path(root)
        self.min_frames = min_frames
        self.meta: dict = {}

    def load_split(self, split: str) -> SplitData:
        data = load_prepared_split(self.root, split)
        self.meta = data.meta
        records = [r for r in data.records() if r.length >= self.min_frames]
        dropped = data.num_clips - len(records)
        if dropped:
            log.info("%s/%s: %d clip(s) shorter than %d frames left out", self.root, split, dropped, self.min_frames)
        return records, data.mean, data.std

    @property
    def num_joints(self) -> int:
        return 22

    @property
    def fps(self) -> float:
        return 20.0

    @property
    def action_names(self) -> list[str]:
        if not self.meta:
            self.dataset("train")
        return list(self.meta["labels"]["content"])


def embedded_data_root() -> Path:
    """data/bandai_mini of the source checkout: the small real dataset the project ships."""
    return Path(__file__).resolve().parents[3] / "data" / "bandai_mini"
