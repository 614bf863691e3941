"""ComputeTime: compute columns in the metrics, and totals that go on across a resumed sitting."""

from __future__ import annotations

import csv

import lightning as L
from lightning.pytorch.demos.boring_classes import BoringModel
from lightning.pytorch.loggers import CSVLogger

from motiondiff.lit.compute_time import ComputeTime, run_totals


def fit(tmp_path, steps, ckpt_path=None, version=0):
    timer = ComputeTime()
    trainer = L.Trainer(max_steps=steps, log_every_n_steps=1, logger=CSVLogger(tmp_path, name="", version=version),
                        callbacks=[timer], enable_progress_bar=False, enable_model_summary=False,
                        default_root_dir=tmp_path)  # fmt: skip
    trainer.fit(BoringModel(), ckpt_path=ckpt_path)
    trainer.save_checkpoint(tmp_path / f"step{steps}.ckpt")
    rows = list(csv.DictReader(open(tmp_path / f"version_{version}" / "metrics.csv")))
    return timer, [float(r["compute/wall_minutes"]) for r in rows if r.get("compute/wall_minutes")]


def test_compute_is_logged_and_a_resumed_run_counts_on_from_its_checkpoint(tmp_path):
    first, walls = fit(tmp_path, 6)
    assert len(walls) >= 5 and walls == sorted(walls) and walls[0] >= 0
    saved_cpu, saved_wall = first.state_dict()["cpu_s"], first.state_dict()["wall_s"]
    assert saved_cpu > 0 and saved_wall > 0
    second, walls = fit(tmp_path, 12, ckpt_path=tmp_path / "step6.ckpt", version=1)
    assert second.cpu_s_before > 0 and second.wall_s_before > 0, "the checkpoint's totals were not restored"
    assert all(w * 60 >= second.wall_s_before for w in walls), "the resumed sitting started counting from zero"


def test_run_json_totals_take_in_the_earlier_sittings(tmp_path):
    fit(tmp_path, 6)
    second, _ = fit(tmp_path, 12, ckpt_path=tmp_path / "step6.ckpt", version=1)
    totals = run_totals([object(), second])
    assert second.wall_s_before > 0 and totals["wall_seconds_all_sittings"] >= round(second.wall_s_before, 1)
    assert second.cpu_s_before > 0 and totals["cpu_seconds_all_sittings"] >= round(second.cpu_s_before, 1)
    assert run_totals([object()]) == {}, "a run without the callback claims compute it did not measure"
