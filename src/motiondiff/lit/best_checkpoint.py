"""The best-metric checkpoint (best FID, best MPJPE) that stays right when a run resumes.

Lightning's ModelCheckpoint restores its top-k list from the checkpoint a run resumes from. The step checkpoint
(last.ckpt) is written at the batch's end and the evaluation runs after it, so a resumed run can miss the best file
its evaluation wrote last: that file then stays beside the next one, and the callback may keep a worse file as "best".
On resuming, this callback rebuilds its top-k list from the files in its folder and the score each file was saved
for (`runtime.best_checkpoints`), then removes the files beyond its top k, as Lightning would have.
"""

from __future__ import annotations

import logging
import os
from pathlib import Path

import torch
from lightning.pytorch.callbacks import ModelCheckpoint

from motiondiff.runtime.best_checkpoints import ranked

log = logging.getLogger(__name__)


class BestCheckpoint(ModelCheckpoint):
    """`ModelCheckpoint` with a monitor and ``save_top_k`` ≥ 1 whose top-k list is rebuilt from its files on resume."""

    @property
    def state_key(self) -> str:
        # Lightning's key names the class: keep ModelCheckpoint's, so runs saved before this callback resume into it
        return super().state_key.replace(type(self).__qualname__, ModelCheckpoint.__qualname__, 1)

    def on_fit_start(self, trainer, pl_module) -> None:
        if trainer.ckpt_path is not None and self.monitor and self.save_top_k > 0 and self.dirpath:
            self.rebuild_top_k(trainer)

    def own_files(self) -> list[Path]:
        """The files this callback's filename pattern names in its folder (not last.ckpt, not half-written ones)."""
        prefix = (self.filename or "").split("{")[0]
        if not prefix or not os.path.isdir(self.dirpath):
            return []  # without a fixed prefix its files cannot be told from the other callbacks'
        last = self.CHECKPOINT_NAME_LAST + self.FILE_EXTENSION
        found = Path(self.dirpath).glob(f"{prefix}*{self.FILE_EXTENSION}")
        return sorted(p for p in found if p.name != last and not p.name.startswith("."))

    def rebuild_top_k(self, trainer) -> None:
        """Take the top k of this folder's files by their stored scores as the callback's list; remove the rest."""
        damaged: list = []  # an unreadable file is left where it is and never chosen
        scored = ranked(self.own_files(), self.monitor, self.mode, damaged)
        for err in damaged:
            log.warning("%s", err)
        if not scored:
            return
        keep, drop = scored[: self.save_top_k], scored[self.save_top_k :]
        self.best_k_models = {os.path.join(self.dirpath, p.name): torch.tensor(s) for s, p in keep}
        self.best_model_score, best = torch.tensor(keep[0][0]), keep[0][1]
        self.best_model_path = os.path.join(self.dirpath, best.name)
        if len(keep) == self.save_top_k:
            self.kth_value, kth = torch.tensor(keep[-1][0]), keep[-1][1]
            self.kth_best_model_path = os.path.join(self.dirpath, kth.name)
        for _, path in drop:
            self._remove_checkpoint(trainer, os.path.join(self.dirpath, path.name))
        if drop:
            log.info("resumed: kept %s (%s %.4g); removed %s, left behind by an earlier sitting", best.name,
                     self.monitor, keep[0][0], ", ".join(p.name for _, p in drop))  # fmt: skip
