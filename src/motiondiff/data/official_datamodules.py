"""Datamodules of the official HumanML3D and KIT-ML folder layouts (new_joint_vecs, texts, split files), as users
bring them; the layouts themselves are read by `motiondiff.data.sources.humanml3d`."""

from __future__ import annotations

from pathlib import Path

from motiondiff.data.datamodules import MotionDataModule, SplitData
from motiondiff.data.sources.humanml3d import HUMANML3D, KIT, OfficialLayout, load_official_split


class OfficialLayoutDataModule(MotionDataModule):
    """A root in the official HumanML3D/KIT-ML layout (see `motiondiff.data.sources.humanml3d`)."""

    layout: OfficialLayout

    def __init__(self, root: str | Path, max_frames: int | None = None, unit_length: int | None = None,
                 representation: str | None = None, **options):  # fmt: skip
        """``options``: MotionDataModule's keywords (batch size, workers, seed, bucketing, ...)."""
        native = "hml263" if self.layout.num_joints == 22 else "kit251"
        if representation not in (None, native):
            raise ValueError(
                f"representation={representation}: the official {self.layout.name} layout stores {native} features "
                f"(new_joint_vecs) only, so use representation={native} (or leave it unset); the rotation and joint-"
                "position representations need a dataset with rotations (humanact12, uestc, bandai, bvh)"
            )
        super().__init__(
            max_frames=self.layout.max_motion_len if max_frames is None else max_frames,
            unit_length=self.layout.unit_length if unit_length is None else unit_length,
            **options,
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
