"""The embedded dataset the repo ships (data/bandai_mini) and its datamodule: no ../shared needed."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch

from motiondiff.data.datamodules import PreparedDataModule, embedded_data_root
from motiondiff.data.formats.prepared import load_split
from motiondiff.runtime.errors import DatasetNotFoundError

ROOT = embedded_data_root()


def test_shipped_files_and_license():
    for name in ("train.npz", "val.npz", "test.npz", "Mean.npy", "Std.npy", "meta.json", "LICENSE", "README.md"):
        assert (ROOT / name).is_file(), name
    size = sum(p.stat().st_size for p in ROOT.iterdir())
    assert size <= 15 * 2**20
    assert "Attribution-NonCommercial 4.0" in (ROOT / "LICENSE").read_text()
    readme = (ROOT / "README.md").read_text()
    assert "Bandai Namco Research Inc., CC BY-NC 4.0" in readme and "generated" in readme


def test_every_content_and_style_is_present():
    meta = json.loads((ROOT / "meta.json").read_text())
    pairs = set()
    for split in ("train", "val", "test"):
        a = load_split(ROOT, split).arrays
        names = [a["dataset_names"][a["dataset"]], a["content_names"][a["content"]], a["style_names"][a["style"]]]
        pairs |= set(zip(*[n.tolist() for n in names], strict=True))  # dataset x content x style
    report = json.loads((ROOT / "report.json").read_text())
    # every dataset x content x style group of both zips (226), two clips where the group has two or more
    assert report["skipped"] == [] and len(pairs) == 226 and sum(report["clips"].values()) == 314
    assert (
        len(meta["labels"]["content"]) == 24
    )  # 16 of ds1 + 10 of ds2, walk and run shared and "generated" in meta["captions"]


def test_datamodule_batches():
    dm = PreparedDataModule(ROOT, batch_size=8, max_frames=64, seed=0)
    dm.setup("fit")
    batch = next(iter(dm.train_dataloader()))
    assert batch["motion"].dtype == torch.float32 and batch["motion"].shape[0] == 8
    assert batch["motion"].shape[2] == dm.feature_dim == 263
    assert batch["mask"].dtype == torch.bool
    assert torch.equal(batch["mask"].sum(1), batch["length"]) and int(batch["length"].max()) <= 64
    assert all(isinstance(t, str) and t for t in batch["text"])
    assert (batch["action"] >= 0).all() and int(batch["action"].max()) < len(dm.action_names)
    # Padding is zero, valid frames are normalised real data.
    assert float(batch["motion"][~batch["mask"]].abs().sum()) == 0.0
    val = next(iter(dm.val_dataloader()))
    assert val["motion"].shape[0] == min(8, len(dm.dataset("val")))


def test_normalisation_round_trip():
    dm = PreparedDataModule(ROOT, batch_size=4)
    ds = dm.dataset("val")
    item = ds[0]
    rec = ds.records[0]
    raw = ds.denormalise(item["motion"].numpy())
    np.testing.assert_allclose(raw, rec.motion[: item["length"]], rtol=1e-5, atol=1e-5)


def test_missing_prepared_folder(tmp_path):
    with pytest.raises(DatasetNotFoundError, match="prepare bandai"):
        PreparedDataModule(tmp_path / "nothing").setup("fit")
