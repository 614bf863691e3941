"""Checkpoints are written beside their target and renamed into place: a save that dies half-way leaves the previous
checkpoint whole and no stray file, and a finished save is one rename (atomic on one filesystem)."""

from __future__ import annotations

import os

import pytest
import torch

from motiondiff.lit.checkpoint_io import AtomicCheckpointIO


def test_a_failed_save_keeps_the_previous_checkpoint(tmp_path, monkeypatch):
    io = AtomicCheckpointIO()
    path = tmp_path / "checkpoints" / "last.ckpt"
    io.save_checkpoint({"global_step": 3, "w": torch.ones(4)}, path)

    def dies_half_way(obj, f, *args, **kwargs):
        with open(f, "wb") as out:
            out.write(b"half a checkpoint")
        raise OSError("killed while writing")

    monkeypatch.setattr(torch, "save", dies_half_way)
    with pytest.raises(OSError, match="killed while writing"):
        io.save_checkpoint({"global_step": 6, "w": torch.zeros(4)}, path)
    monkeypatch.undo()
    assert io.load_checkpoint(path, weights_only=True)["global_step"] == 3
    assert sorted(p.name for p in path.parent.iterdir()) == ["last.ckpt"]


def test_a_save_is_one_rename_within_the_folder(tmp_path, monkeypatch):
    renames = []
    real = os.replace
    monkeypatch.setattr(os, "replace", lambda a, b: (renames.append((str(a), str(b))), real(a, b))[1])
    path = tmp_path / "step0000003.ckpt"
    AtomicCheckpointIO().save_checkpoint({"global_step": 3}, path)
    ((src, dst),) = renames
    assert dst == str(path) and os.path.dirname(src) == str(tmp_path)
