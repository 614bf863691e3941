"""Exact resumes: a run killed after a checkpoint and resumed from it ends with the weights an uninterrupted run
would have.

Lightning restores the weights, optimizer, schedulers and step counters. Two things it leaves out are saved here
in every checkpoint: where the training order stood (the epoch and how many of its batches were used; the train
loader's `EpochShuffleSampler` rebuilds the rest of that epoch) and the random state of torch, numpy and Python
(diffusion time steps, noise, dropout, condition drop). The random state is put back just before the first
training batch after the restore, so nothing Lightning draws while setting up can shift it.
"""

from __future__ import annotations

import random

import lightning as L
import numpy as np
import torch

from motiondiff.runtime.errors import UsageError

KEY = "motiondiff_resume"


def random_state() -> dict:
    """Every global generator's state as plain values (loads with torch.load(weights_only=True))."""
    kind, keys, pos, has_gauss, gauss = np.random.get_state()  # noqa: NPY002 (the legacy global: other code may use it)
    version, state, gauss_py = random.getstate()
    return {"torch": torch.get_rng_state(), "numpy": [kind, keys.tolist(), pos, has_gauss, gauss],
            "python": [version, list(state), gauss_py]}  # fmt: skip


def set_random_state(saved: dict) -> None:
    torch.set_rng_state(saved["torch"])
    kind, keys, pos, has_gauss, gauss = saved["numpy"]
    np.random.set_state((kind, np.array(keys, dtype=np.uint32), pos, has_gauss, gauss))  # noqa: NPY002
    version, state, gauss_py = saved["python"]
    random.setstate((version, tuple(state), gauss_py))


class ExactResume(L.Callback):
    def __init__(self):
        self._pending: dict | None = None

    def on_save_checkpoint(self, trainer: L.Trainer, pl_module, checkpoint: dict) -> None:
        done = trainer.fit_loop.epoch_loop.batch_progress.current.processed  # batches of this epoch stepped on
        epoch = trainer.current_epoch
        if done >= trainer.num_training_batches:  # saved at the end of an epoch: resume at the next one
            epoch, done = epoch + 1, 0
        checkpoint[KEY] = {"epoch": epoch, "batches_done": done, "batch_size": trainer.datamodule.batch_size,
                           "random_state": random_state()}  # fmt: skip

    def on_load_checkpoint(self, trainer: L.Trainer, pl_module, checkpoint: dict) -> None:
        saved = checkpoint.get(KEY)
        if saved is None:  # a checkpoint from before exact resumes: Lightning's own resume
            return
        if saved["batch_size"] != trainer.datamodule.batch_size:
            raise UsageError(f"the checkpoint was trained with batch_size={saved['batch_size']}: resume with the same "
                             f"batch_size (got {trainer.datamodule.batch_size}) or use init_from= to fine-tune")  # fmt: skip
        trainer.datamodule.resume_position = (saved["epoch"], saved["batches_done"] * saved["batch_size"])
        self._pending = saved["random_state"]

    def on_train_batch_start(self, trainer: L.Trainer, pl_module, batch, batch_idx: int) -> None:
        if self._pending is not None:
            set_random_state(self._pending)
            self._pending = None
