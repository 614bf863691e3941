"""Dataset-agnostic motion records, the torch Dataset over them, and the padding collate.

Every dataset loader (the prepared npz of Bandai/BVH data, the official HumanML3D/KIT layouts, ...) turns its files
into a list of `MotionRecord`s plus Mean/Std; `MotionDataset` and `collate_motion` are shared by all of them, so a
batch always looks the same: {motion [B,N,D], mask [B,N], length [B], text [B], action [B], id [B]}.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import torch
from torch.utils.data import Dataset

NO_ACTION = -1


@dataclass
class MotionRecord:
    id: str
    motion: np.ndarray  # (N, D) features, not normalised
    texts: list[str] = field(default_factory=list)  # captions; several per clip are sampled at random in training
    action: int = NO_ACTION
    meta: dict = field(default_factory=dict)  # anything dataset-specific (labels, tokens, source file)

    @property
    def length(self) -> int:
        return int(self.motion.shape[0])


class MotionDataset(Dataset):
    """Normalised, optionally randomly cropped motion clips with one caption each.

    `train=True`: a random caption and (for clips longer than `max_frames`) a random window each time;
    `train=False`: the first caption and the first window, so evaluation is repeatable.
    `window_min_frames` (train only): the window length is also random, uniform in [min(length, window_min_frames),
    min(length, max_frames)]. Without it every clip longer than `max_frames` is seen at exactly `max_frames`, so
    where long clips are of other actions than short ones (Bandai: walks 130-210 frames, runs 50-100) the model
    learns the length as a cue for the action, and a 4 s walk comes out as a run.
    `first_window_share` (train only): that share of the windows is the clip's first min(length, max_frames)
    frames, the window the evaluation and a user's request of that length see (a motion from its start); the rest
    are random as above.
    Lengths are rounded down to a multiple of `unit_length` (the official HumanML3D loader uses 4).
    """

    def __init__(
        self,
        records: list[MotionRecord],
        mean: np.ndarray,
        std: np.ndarray,
        max_frames: int = 196,
        unit_length: int = 1,
        train: bool = True,
        seed: int = 0,
        window_min_frames: int | None = None,
        first_window_share: float = 0.0,
    ):
        if not records:
            raise ValueError("MotionDataset got no clips: check the split file and the length limits")
        dim = records[0].motion.shape[1]
        if mean.shape != (dim,) or std.shape != (dim,):
            raise ValueError(f"Mean/Std have shapes {mean.shape}/{std.shape} but the features have {dim} dims")
        self.records = records
        self.mean = mean.astype(np.float32)
        self.std = np.where(std < 1e-8, 1.0, std).astype(np.float32)  # constant dims stay finite
        self.max_frames = max_frames
        self.unit_length = unit_length
        if window_min_frames is not None and window_min_frames < 1:
            raise ValueError(f"window_min_frames must be a positive number of frames or null, got {window_min_frames}")
        self.window_min_frames = window_min_frames
        if not 0.0 <= first_window_share <= 1.0:
            raise ValueError(f"first_window_share must be a share in [0, 1], got {first_window_share}")
        self.first_window_share = float(first_window_share)
        self.train = train
        self.seed = int(seed or 0)
        self.rng = np.random.default_rng(seed)

    def __len__(self) -> int:
        return len(self.records)

    def normalise(self, motion: np.ndarray) -> np.ndarray:
        return (motion - self.mean) / self.std

    def normalised_range(self) -> tuple[np.ndarray, np.ndarray]:
        """Per-feature (min, max) of the normalised clips: the range a sampler may clip x̂0 to (`diffusion.clip_x0`)."""
        low = np.min([r.motion.min(0) for r in self.records], axis=0)
        high = np.max([r.motion.max(0) for r in self.records], axis=0)
        return self.normalise(low).astype(np.float32), self.normalise(high).astype(np.float32)

    def denormalise(self, motion):
        if isinstance(motion, torch.Tensor):
            return motion * torch.as_tensor(self.std, device=motion.device) + torch.as_tensor(
                self.mean, device=motion.device
            )
        return motion * self.std + self.mean

    def _item_rng(self, epoch: int, index: int) -> np.random.Generator:
        return np.random.default_rng((self.seed, int(epoch), int(index)))

    @property
    def draws_window_lengths(self) -> bool:
        """Whether an item's length is drawn (training with random window lengths or a share of first windows), so
        that it depends on the item's own random draws."""
        return self.train and (self.window_min_frames is not None or self.first_window_share > 0)

    def _window(self, rec: MotionRecord, rng: np.random.Generator) -> tuple[int, bool]:
        """(frames, whether the window is the clip's first): the first draws of ``rng``, so `item_lengths` can
        repeat them. No draw is added where `first_window_share` is 0, so earlier runs resume unchanged."""
        n = min(rec.length, self.max_frames)
        first = not self.train
        if self.draws_window_lengths:
            first = self.first_window_share > 0 and rng.random() < self.first_window_share
            if not first and self.window_min_frames is not None:
                n = int(rng.integers(min(n, self.window_min_frames), n + 1))
        return max(self.unit_length, n - n % self.unit_length), first

    def item_lengths(self, epoch: int) -> np.ndarray:
        """Frames of every item of ``epoch``: the ``length`` that ``self[(epoch, i)]`` returns, without building the
        items (a length-bucketing sampler groups by it). Fixed unless training windows have random lengths."""
        if self.draws_window_lengths:
            lengths = [self._window(r, self._item_rng(epoch, i))[0] for i, r in enumerate(self.records)]
        else:  # no draw: self.rng is not touched
            lengths = [self._window(r, self.rng)[0] for r in self.records]
        return np.asarray(lengths, dtype=np.int64)

    def __getitem__(self, key: int | tuple[int, int]) -> dict:
        """``key``: a clip index, or (epoch, index) from `EpochShuffleSampler`, in which case the random window and
        caption come from (seed, epoch, index) alone, so a resumed run draws what the interrupted one would have."""
        if isinstance(key, tuple):
            epoch, index = key
            rng = self._item_rng(epoch, index)
        else:
            index, rng = key, self.rng
        rec = self.records[index]
        n, first = self._window(rec, rng)  # the first draws of rng, so `item_lengths` can repeat them
        start = 0
        if self.train and not first and rec.length > n:
            start = int(rng.integers(0, rec.length - n + 1))
        motion = self.normalise(rec.motion[start : start + n])
        if rec.texts:
            text = rec.texts[int(rng.integers(len(rec.texts)))] if self.train else rec.texts[0]
        else:
            text = ""
        return {
            "motion": torch.from_numpy(np.ascontiguousarray(motion, dtype=np.float32)),
            "length": n,
            "text": text,
            "action": rec.action,
            "id": rec.id,
            "start": start,  # with id and length, names the exact window (latent caches key on it)
        }


def collate_motion(items: list[dict]) -> dict:
    """Pad to the longest clip of the batch; mask is True on valid frames."""
    lengths = torch.tensor([it["length"] for it in items], dtype=torch.long)
    n_max = int(lengths.max())
    dim = items[0]["motion"].shape[1]
    motion = torch.zeros(len(items), n_max, dim)
    for i, it in enumerate(items):
        motion[i, : it["length"]] = it["motion"]
    mask = torch.arange(n_max)[None, :] < lengths[:, None]
    return {
        "motion": motion,
        "mask": mask,
        "length": lengths,
        "text": [it["text"] for it in items],
        "action": torch.tensor([it["action"] for it in items], dtype=torch.long),
        "id": [it["id"] for it in items],
        "start": torch.tensor([it.get("start", 0) for it in items], dtype=torch.long),
    }
