"""Datamodules of the action datasets MDM and ACTOR use, in their pickled layouts (HumanAct12, UESTC).

Both store SMPL rotations, so every representation works; MDM trains them on 6D rotations + root (rp6jr, the
default here). Captions are GENERATED from the action names (marked so in each record's meta).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from motiondiff.data.datamodules import ClipDataModule
from motiondiff.data.representations.clip import ClipSplit
from motiondiff.data.sources.humanact12 import load_humanact12
from motiondiff.data.sources.uestc import load_uestc


class _ActionClipDataModule(ClipDataModule):
    """`normalise=False` feeds the features as they are (mean 0, std 1): MDM's a2m data are not normalised, so its
    presets train on raw 6D rotations and metres, where the geometric losses' λ = 1 has the paper's meaning."""

    default_representation = "rp6jr"

    def __init__(self, root: str | Path, max_frames: int = 60, normalise: bool = True, **options):
        """``options``: ClipDataModule's and MotionDataModule's keywords."""
        super().__init__(max_frames=max_frames, **options)
        self.root = Path(root)
        self.normalise = bool(normalise)

    def statistics(self) -> tuple[np.ndarray, np.ndarray]:
        mean, std = super().statistics()
        if self.normalise:
            return mean, std
        return np.zeros_like(mean), np.ones_like(std)


class HumanAct12DataModule(_ActionClipDataModule):
    """`<root>/humanact12poses.pkl` (ACTOR's HumanAct12Poses); see motiondiff.data.sources.humanact12 for the layout."""

    def load_clips(self, split: str) -> ClipSplit:
        return load_humanact12(self.root, split)


class UESTCDataModule(_ActionClipDataModule):
    """`<root>/vibe_cache_refined.pkl` + `<root>/info/` (ACTOR's UESTC); cross-subject split as ACTOR reads it."""

    def load_clips(self, split: str) -> ClipSplit:
        return load_uestc(self.root, split, num_frames=self.max_frames)
