"""Lightning datamodules: one base that turns `load_split` output into loaders, one subclass per dataset.

Every datamodule yields the same batch (see `collate_motion`): motion [B,N,D] float32 (normalised),
mask [B,N] bool, length [B], text list[str], action [B] long, id list[str].
"""

from __future__ import annotations

import abc
import logging
from dataclasses import replace
from pathlib import Path

import lightning as L
import numpy as np
from torch.utils.data import DataLoader

from motiondiff.data.datasets import MotionDataset, MotionRecord
from motiondiff.data.formats.joint_map import JointMap
from motiondiff.data.formats.prepared import PreparedSplit
from motiondiff.data.formats.prepared import load_split as load_prepared_split
from motiondiff.data.loaders import motion_loader
from motiondiff.data.mirror import with_mirrors
from motiondiff.data.preparing.from_bvh import ensure_prepared_bvh
from motiondiff.data.representations import Representation, get_representation
from motiondiff.data.representations.clip import ClipSplit, LabelledClip
from motiondiff.data.representations.hml_features import mean_std
from motiondiff.data.representations.spec import HMLBridge, bridge_from_spec, representation_spec
from motiondiff.geometry.skeleton import SMPL22
from motiondiff.runtime.errors import DatasetNotFoundError
from motiondiff.runtime.paths import REPO_DIR

log = logging.getLogger(__name__)

SplitData = tuple[list[MotionRecord], np.ndarray, np.ndarray]
MIRRORED_REPRESENTATIONS = ("hml263", "kit251")  # features whose mirror is a signed permutation (data.mirror)
_STAGE_SPLITS = {"fit": ("train", "val"), "validate": ("val",), "test": ("test",), "predict": ("test",)}


class MotionDataModule(L.LightningDataModule, abc.ABC):
    """Base: subclasses only say how to read a split (`load_split`) and the skeleton facts.

    `load_split` must return the training-set statistics for every split (the official layouts ship one
    Mean/Std); val/test are normalised with them, and a split that returns different statistics is an error.
    `bucketing`: training batches of similar-length clips, sorted in chunks of `bucket_chunk` batches
    (`motiondiff.data.bucketing`); far less padding where clip lengths vary.
    `mirror`: the train split also holds every clip's left-right mirror image (`motiondiff.data.mirror`), and
    Mean/Std are those of the doubled train split, as HumanML3D's; val and test stay the real clips.
    """

    def __init__(
        self,
        batch_size: int = 64,
        num_workers: int = 0,
        max_frames: int = 196,
        unit_length: int = 4,
        seed: int = 0,
        balance: float = 0.0,
        window_min_frames: int | None = None,
        first_window_share: float = 0.0,
        bucketing: bool = False,
        bucket_chunk: int = 64,
        mirror: bool = False,
    ):
        super().__init__()
        self.mirror = bool(mirror)
        self._mirror_stats: tuple[np.ndarray, np.ndarray] | None = None
        self.bucketing, self.bucket_chunk = bool(bucketing), int(bucket_chunk)
        self.window_min_frames = window_min_frames  # random training-window lengths: MotionDataset
        self.first_window_share = float(first_window_share)  # share of windows that are the clip's first: ditto
        self.balance = float(balance)  # class-balanced training order: resumable.balance_weights
        self.batch_size = batch_size
        self.num_workers = num_workers
        self.max_frames = max_frames
        # (epoch, samples already used in it) for the next train loader: set when a run resumes (lit.resume)
        self.resume_position: tuple[int, int] | None = None
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

    def representation_spec(self) -> dict | None:
        """What a checkpoint stores to decode samples (None: HumanML3D features of `feature_dim`)."""
        return None

    def evaluation_bridge(self) -> HMLBridge:
        """Turns this datamodule's features into the HumanML3D features the evaluators read."""
        return bridge_from_spec(None, self.feature_dim)

    def model_hparams(self, name: str) -> dict:
        """What a model must carry from its training data to generate without it: feature width and Mean/Std, length
        limit, frame rate, joints, dataset name and representation."""
        ds = self.dataset("train")
        return dict(feature_dim=self.feature_dim, mean=ds.mean.tolist(), std=ds.std.tolist(),
                    max_frames=self.max_frames, fps=self.fps, num_joints=self.num_joints, dataset=name,
                    representation=self.representation_spec())  # fmt: skip

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

    def mirror_label_names(self) -> list[str]:
        """Action names whose left/right images swap under `mirror` (none for caption-only datasets)."""
        return []

    def dataset(self, split: str) -> MotionDataset:
        """The MotionDataset of a split, loaded once."""
        if split not in self.datasets:
            if self.mirror and split != "train":
                self.dataset("train")  # the statistics are the doubled train split's
            records, mean, std = self.load_split(split)
            if self.mirror:
                if split == "train":
                    records = with_mirrors(records, self.mirror_label_names())
                    self._mirror_stats = mean_std(np.concatenate([r.motion for r in records]))
                mean, std = self._mirror_stats
            self._set_stats(split, mean, std)
            self.datasets[split] = MotionDataset(
                records,
                mean,
                std,
                max_frames=self.max_frames,
                unit_length=self.unit_length,
                train=split == "train",
                seed=self.seed,
                window_min_frames=self.window_min_frames,
                first_window_share=self.first_window_share,
            )
        return self.datasets[split]

    def setup(self, stage: str | None = None) -> None:
        splits = _STAGE_SPLITS.get(stage or "", ("train", "val", "test"))  # None: every split
        for split in splits:
            self.dataset(split)

    def _loader(self, split: str) -> DataLoader:
        train = split == "train"
        resume = self.resume_position if train else None  # one train loader starts where the checkpoint was
        if train:
            self.resume_position = None
        return motion_loader(self.dataset(split), self.batch_size, train=train, seed=self.seed,
                             num_workers=self.num_workers, balance=self.balance, bucketing=self.bucketing,
                             bucket_chunk=self.bucket_chunk, resume_position=resume)  # fmt: skip

    def train_dataloader(self) -> DataLoader:
        return self._loader("train")

    def val_dataloader(self) -> DataLoader:
        return self._loader("val")

    def test_dataloader(self) -> DataLoader:
        return self._loader("test")

    def predict_dataloader(self) -> DataLoader:
        return self._loader("test")


class ClipDataModule(MotionDataModule, abc.ABC):
    default_representation = "hml263"

    def __init__(self, min_frames: int = 16, representation: str | None = None, unit_length: int = 1, **options):
        """``options``: MotionDataModule's keywords (batch size, workers, max_frames, seed, balance, windows,
        bucketing, mirror), declared once there."""
        super().__init__(unit_length=unit_length, **options)
        self.min_frames = min_frames
        self.representation_name = representation or self.default_representation
        if self.mirror and self.representation_name not in MIRRORED_REPRESENTATIONS:
            raise ValueError(
                f"mirror=true reflects HumanML3D/KIT-ML features; representation={self.representation_name} has no "
                f"mirror here: use representation=hml263 (or kit251), or mirror=false"
            )
        self._splits: dict[str, ClipSplit] = {}
        self._rep: Representation | None = None
        self._train_features: list[np.ndarray] | None = None

    @abc.abstractmethod
    def load_clips(self, split: str) -> ClipSplit:
        """The clips of `split` ('train', 'val' or 'test')."""

    def joint_map(self) -> JointMap | None:
        """Rig joints -> feature-skeleton joints, for evaluation of rig representations (None: rig starts with them)."""
        return None

    # ---- clips and representation ---------------------------------------------------------------------------
    def clips(self, split: str) -> ClipSplit:
        if split not in self._splits:
            self._splits[split] = self.load_clips(split)
        return self._splits[split]

    @property
    def representation(self) -> Representation:
        if self._rep is None:
            train = self.clips("train")
            self._rep = get_representation(self.representation_name, train.feature_skeleton, train.rig)
        return self._rep

    def representation_spec(self) -> dict:
        return representation_spec(self.representation, self.clips("train").feature_skeleton, self.joint_map())

    def evaluation_bridge(self) -> HMLBridge:
        """Turns this datamodule's features into the HumanML3D features the evaluators read."""
        return HMLBridge(self.representation, self.clips("train").feature_skeleton, self.joint_map())

    def encode(self, split: str) -> list[np.ndarray]:
        """Features of every clip of `split`, not normalised (subclasses may serve precomputed ones)."""
        rep = self.representation
        return [rep.encode(c.motion) for c in self.clips(split).clips]

    def load_split(self, split: str) -> SplitData:
        data = self.clips(split)
        features = self.encode(split)
        if split == "train":
            self._train_features = features
        records = [
            MotionRecord(id=c.id, motion=f, texts=list(c.texts), action=c.action, meta=dict(c.meta or {}))
            for c, f in zip(data.clips, features, strict=True)
            if len(f) >= self.min_frames
        ]
        dropped = len(data.clips) - len(records)
        if dropped:
            log.info("%s/%s: %d clip(s) shorter than %d frames left out", type(self).__name__, split, dropped,
                     self.min_frames)  # fmt: skip
        mean, std = self.statistics()
        return records, mean, std

    def statistics(self) -> tuple[np.ndarray, np.ndarray]:
        """Mean/Std of the train split's features in the chosen representation."""
        if self._train_features is None:
            self._train_features = self.encode("train")
        return self.representation.mean_std(np.concatenate(self._train_features))

    # ---- facts the model is built from ---------------------------------------------------------------------
    @property
    def feature_dim(self) -> int:
        return self.representation.dim

    @property
    def num_joints(self) -> int:
        return self.clips("train").feature_skeleton.num_joints

    @property
    def fps(self) -> float:
        return float(self.clips("train").fps)

    @property
    def action_names(self) -> list[str]:
        return list(self.clips("train").action_names)

    def mirror_label_names(self) -> list[str]:
        return self.action_names


class PreparedDataModule(ClipDataModule):
    """A folder written by `python -m motiondiff.data.preparing.prepare` (Bandai, the embedded bandai_mini, BVH folders).

    Clips shorter than `min_frames` are left out of training and evaluation (logged with their count); the
    captions are GENERATED ones (see motiondiff.data.preparing.captions) and each record says so in its meta. HumanML3D
    features (the default representation) are read as prepared, with the prepared Mean/Std; any other
    representation is encoded from the stored joints and native rotations.
    """

    def __init__(self, root: str | Path, extra_train: list[str | Path] | None = None, **options):
        """``options``: ClipDataModule's and MotionDataModule's keywords."""
        super().__init__(**options)
        self.root = Path(root)
        self.meta: dict = {}
        self._prepared: dict[str, PreparedSplit] = {}
        # prepared folders whose train clips join this train split (bandai_mini's single clips beside composed ones)
        self.extra_train = [Path(p) for p in extra_train or ()]
        self._extra: dict[Path, PreparedSplit] = {}

    def prepared(self, split: str) -> PreparedSplit:
        if split not in self._prepared:
            self._prepared[split] = load_prepared_split(self.root, split)
            self.meta = self._prepared[split].meta
        return self._prepared[split]

    def _parts(self, split: str) -> list[PreparedSplit]:
        """The split, and on train the extra_train folders' train splits (loaded once)."""
        if split != "train":
            return [self.prepared(split)]
        for r in self.extra_train:
            self._extra[r] = self._extra.get(r) or load_prepared_split(r, "train")
        return [self.prepared(split)] + [self._extra[r] for r in self.extra_train]

    def load_clips(self, split: str) -> ClipSplit:
        data, parts = self.prepared(split), self._parts(split)
        rig = self.prepared("train").rig()
        names = list(data.meta["labels"]["content"])
        if any(list(d.meta["labels"]["content"]) != names for d in parts):  # action ids index one list
            raise ValueError(f"extra_train folders {self.extra_train} must have the content labels of {self.root}")
        clips = [
            LabelledClip(r.id, replace(c, rig=rig), r.texts, r.action, r.meta)
            for d in parts
            for r, c in zip(d.records(), d.clips(), strict=True)
        ]
        return ClipSplit(clips, names, fps=float(data.meta.get("fps", 20.0)), feature_skeleton=SMPL22, rig=rig)

    def encode(self, split: str) -> list[np.ndarray]:
        if self.representation_name != "hml263":
            return super().encode(split)
        # the prepared features: same function, already computed
        return [d.arrays["features"][d.feature_slice(i)] for d in self._parts(split) for i in range(d.num_clips)]

    def statistics(self) -> tuple[np.ndarray, np.ndarray]:
        if self.representation_name != "hml263":
            return super().statistics()
        data = self.prepared("train")
        return data.mean, data.std

    def joint_map(self) -> JointMap | None:
        """The map the dataset was prepared with: its joint_map.json (BVH folders), or the shipped 'source_to_target'."""
        self.prepared("train")
        if (self.root / "joint_map.json").is_file():
            return JointMap.load(self.root / "joint_map.json")
        source, target = str(self.meta.get("joint_map", "bandai->smpl22")).split("->")
        return JointMap.load(f"{source}_to_{target}")


class BVHDataModule(PreparedDataModule):
    """Any folder or zip of BVH files (100STYLE, Bandai, your own capture) with an optional labels CSV.

    The files are prepared once into `cache` (`python -m motiondiff.data.preparing.prepare bvh` does the same by hand; see
    motiondiff.data.preparing.from_bvh for the labels format and how labels are read from paths) and reused while the
    sources and options stay the same.
    """

    def __init__(self, src: str | Path, cache: str | Path, labels: str | Path | None = None, joint_map: str = "auto",
                 max_clip_frames: int | None = None, up_axis: str = "auto", **options):  # fmt: skip
        """``options``: PreparedDataModule's keywords (batch size, max_frames, min_frames, representation, ...)."""
        super().__init__(cache, **options)
        self.src, self.labels, self.joint_map_spec, self.max_clip_frames = src, labels, joint_map, max_clip_frames
        self.up_axis = up_axis

    def prepared(self, split: str) -> PreparedSplit:
        if not self._prepared:
            if not Path(self.src).exists():
                raise DatasetNotFoundError(
                    self.src, dataset="bvh", how_to_get="any motion capture exported as BVH (100STYLE, Bandai, ...)",
                    layout="  <src>/**/*.bvh (a folder or a .zip), optional labels CSV: file,action,style,caption",
                )  # fmt: skip
            ensure_prepared_bvh(self.src, self.root, labels=self.labels, joint_map=self.joint_map_spec,
                                max_frames=self.max_clip_frames, seed=self.seed, up_axis=self.up_axis)  # fmt: skip
        return super().prepared(split)


def embedded_data_root() -> Path:
    """data/bandai_mini of the source checkout: the small real dataset the project ships."""

    return REPO_DIR / "data" / "bandai_mini"
