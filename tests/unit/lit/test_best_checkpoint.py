"""The best-metric checkpoint across a resume: the resumed run's last.ckpt was written before the evaluation that
made the newest best file, so Lightning's own callback would keep that file beside a worse "best" one."""

from __future__ import annotations

import lightning as L
import torch
from lightning.pytorch.callbacks import ModelCheckpoint
from lightning.pytorch.demos.boring_classes import BoringModel

from motiondiff.lit.best_checkpoint import BestCheckpoint
from motiondiff.model_files.resolve import find_model
from motiondiff.runtime.best_checkpoints import best_of, stored_score


class ScriptedFid(BoringModel):
    """Logs the next of ``fids`` as val/fid at each evaluation."""

    def __init__(self, fids):
        super().__init__()
        self.fids = list(fids)

    def on_validation_epoch_end(self):
        self.log("val/fid", self.fids.pop(0) if self.fids else 9.0)


def fit(folder, steps, fids, best_class, ckpt_path=None):
    steps_ckpt = ModelCheckpoint(dirpath=folder, filename="step{step:07d}", auto_insert_metric_name=False,
                                 every_n_train_steps=4, save_top_k=-1, save_last=True)  # fmt: skip
    best = best_class(dirpath=folder, filename="best-fid-step{step:07d}", auto_insert_metric_name=False,
                      monitor="val/fid", mode="min", save_top_k=1, save_on_train_epoch_end=False)  # fmt: skip
    trainer = L.Trainer(max_steps=steps, limit_train_batches=4, limit_val_batches=1, num_sanity_val_steps=0,
                        callbacks=[steps_ckpt, best], logger=False, enable_progress_bar=False,
                        enable_model_summary=False, default_root_dir=folder)  # fmt: skip
    trainer.fit(ScriptedFid(fids), ckpt_path=ckpt_path)
    return best


def test_a_resumed_run_keeps_one_best_file_the_lowest_fid(tmp_path):
    folder = tmp_path / "checkpoints"
    # the first sitting as runs were saved before this callback (Lightning's own): FID 5 at step 4, 3 at step 8
    fit(folder, 8, [5.0, 3.0], ModelCheckpoint)
    assert sorted(p.name for p in folder.glob("best-fid-*")) == ["best-fid-step0000008.ckpt"]
    saved = torch.load(folder / "last.ckpt", map_location="cpu", weights_only=True)
    stale = next(v for k, v in saved["callbacks"].items() if "val/fid" in k)
    assert stale["best_model_score"].item() == 5.0, "last.ckpt no longer predates the evaluation: scenario changed"
    # the next sitting resumes from that last.ckpt and evaluates worse than step 8 but better than its stale record
    best = fit(folder, 16, [4.0, 4.5, 4.2], BestCheckpoint, ckpt_path=folder / "last.ckpt")
    kept = sorted(folder.glob("best-fid-*"))
    assert [p.name for p in kept] == ["best-fid-step0000008.ckpt"], kept
    assert stored_score(kept[0], "val/fid") == 3.0 and best.best_model_score.item() == 3.0
    assert best.best_model_path == str(kept[0])


def test_a_resume_removes_a_stale_best_file_and_keeps_the_better_one(tmp_path):
    folder = tmp_path / "checkpoints"
    fit(folder, 8, [5.0, 3.0], ModelCheckpoint)
    # a stale best file the first sitting left (worse than step 8's)
    (folder / "best-fid-step0000004.ckpt").write_bytes((folder / "step0000004.ckpt").read_bytes())
    state = torch.load(folder / "best-fid-step0000004.ckpt", map_location="cpu", weights_only=True)
    next(v for k, v in state["callbacks"].items() if "val/fid" in k)["current_score"] = torch.tensor(5.0)
    torch.save(state, folder / "best-fid-step0000004.ckpt")
    fit(folder, 12, [2.0], BestCheckpoint, ckpt_path=folder / "last.ckpt")
    assert sorted(p.name for p in folder.glob("best-fid-*")) == ["best-fid-step0000012.ckpt"]


def test_checkpoint_best_names_the_lowest_stored_fid_not_the_newest_name(tmp_path):
    run = tmp_path / "outputs" / "train" / "run" / "checkpoints"
    fit(run, 8, [3.0, 5.0], ModelCheckpoint)
    better = run / "best-fid-step0000004.ckpt"
    worse = run / "best-fid-step0000012.ckpt"  # a later name, a worse score: left behind by a resumed sitting
    state = torch.load(better, map_location="cpu", weights_only=True)
    next(v for k, v in state["callbacks"].items() if "val/fid" in k)["current_score"] = torch.tensor(7.0)
    torch.save(state, worse)
    assert best_of([worse, better, run / "last.ckpt"], "val/fid") == better
    assert find_model("best", tmp_path / "outputs") == better
