"""Issue 43's ablation cells (conf/experiment/ablation_full.yaml): the preset holds the rules of
docs/results/ablation_plan.md, and a (tiny) cell evaluates by steps across epochs, checkpoints after each evaluation
with the stopping rule's history, and stops when the rule says so. No test trains a real cell."""

from __future__ import annotations

import pytest
import torch
from fixtures.in_process import run_entry
from fixtures.tiny_models import TINY
from hydra import compose, initialize_config_dir
from hydra.utils import instantiate

from motiondiff.cli.common import REPO_DIR, register_resolvers
from motiondiff.data.datamodules import MIRRORED_REPRESENTATIONS


def test_the_cell_preset_holds_the_plans_rules():
    register_resolvers()
    with initialize_config_dir(config_dir=str(REPO_DIR / "conf"), version_base="1.3"):
        cfg = compose("train", overrides=["experiment=ablation_full", "ablation=x0_hml263"])
    plateau, trainer = cfg.callbacks.plateau, cfg.trainer
    assert (trainer.val_check_interval, trainer.check_val_every_n_epoch, trainer.max_steps) == (1000, None, 15000)
    assert (plateau.monitor, plateau.mode, plateau.min_gain, plateau.window, plateau.start) == ("val/fid", "min", 0.05,
                                                                                                3000, 4000)  # fmt: skip
    assert cfg.dataset.name == "bandai" and cfg.dataset.datamodule.mirror and cfg.model.d_model == 128
    assert list(cfg.callbacks).index("plateau") > list(cfg.callbacks).index("evaluation")


def test_a_cell_evaluates_by_steps_checkpoints_each_evaluation_and_stops_on_the_plateau(tmp_path):
    # 8 clips a batch on the embedded data: an epoch is 63 steps, so evaluations every 2 steps fall inside epochs
    _, run = run_entry("train", tmp_path, "experiment=ablation_full", "ablation=x0_hml263", "dataset=bandai_mini",
                       *TINY, "batch_size=8", "trainer.max_steps=40", "trainer.val_check_interval=2",
                       "trainer.precision=32-true", "callbacks.evaluation.num_clips=4", "callbacks.evaluation.steps=2",
                       "callbacks.evaluation.action_accuracy=false", "callbacks.plateau.window=2",
                       "callbacks.plateau.start=2", "callbacks.plateau.min_gain=0.99")  # fmt: skip
    ckpts = run / "checkpoints"
    assert sorted(p.name for p in ckpts.glob("step*.ckpt")) == ["step0000002.ckpt", "step0000004.ckpt"]

    def saved(name):
        checkpoint = torch.load(ckpts / name, map_location="cpu", weights_only=False)
        return checkpoint["global_step"], checkpoint["callbacks"]["PlateauStop"]["history"]

    step, history = saved("last.ckpt")
    assert step == 4 and [s for s, _ in history] == [2, 4]  # stopped at 4: no 99 % gain over the last 2 steps
    assert [s for s, _ in saved("step0000002.ckpt")[1]] == [2]  # each checkpoint holds the evaluations so far
    assert list(ckpts.glob("best-fid-*.ckpt"))


@pytest.mark.parametrize("cell", sorted(p.stem for p in (REPO_DIR / "conf" / "ablation").glob("*.yaml")))
def test_every_cell_builds_its_datamodule_mirroring_only_what_has_an_exact_mirror(cell):
    # the first try of the jp/rp6jr/rpqjr cells stopped at once on the preset's mirror: true (ablation_plan.md)
    register_resolvers()
    with initialize_config_dir(config_dir=str(REPO_DIR / "conf"), version_base="1.3"):
        cfg = compose("train", overrides=["experiment=ablation_full", f"ablation={cell}"])
    datamodule = instantiate(cfg.dataset.datamodule)  # builds nothing from data yet; refuses a mirror it cannot do
    assert datamodule.representation_name == cfg.representation
    assert datamodule.mirror == (cfg.representation in MIRRORED_REPRESENTATIONS)
