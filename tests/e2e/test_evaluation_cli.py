"""Evaluation end to end: the best-FID checkpoint while training, evaluate.py's table, the guidance sweep plot."""

from __future__ import annotations

import csv
import json

import pytest
import torch
from cli_helpers import REPO, TINY, run_cli
from fixtures.in_process import run_entry, user_error

EVALUATORS = REPO / "checkpoints" / "evaluators" / "bandai_mini"
FAST_EVAL = ["callbacks.evaluation.num_clips=12", "callbacks.evaluation.steps=4", "callbacks.evaluation.videos=null"]

pytestmark = pytest.mark.skipif(
    not (EVALUATORS / "text_motion.safetensors").is_file(),
    reason=f"no shipped evaluators in {EVALUATORS}: rebuild them with python -m motiondiff.cli.train_evaluator",
)


@pytest.mark.slow
def test_best_fid_checkpoint_is_the_lowest_logged_fid(tmp_path):
    # 4 training steps per epoch on the embedded data; evaluation after every epoch, 5 evaluations in all.
    proc = run_cli("train.py", *TINY, "trainer.max_steps=20", "trainer.check_val_every_n_epoch=1",
                   "checkpoint_every=100", "optim.lr=2e-3", *FAST_EVAL, env_dir=tmp_path)  # fmt: skip
    assert "evaluation at step 4: " in proc.stderr, "the in-training evaluation shows no progress"  # its tqdm bar
    run = next((tmp_path / "outputs").glob("train/*"))
    rows = list(csv.DictReader(open(next(run.glob("csv/version_*/metrics.csv")))))
    fids = {int(r["step"]): float(r["val/fid"]) for r in rows if r.get("val/fid")}
    assert len(fids) >= 4, f"expected an FID per evaluation, got {fids}"
    for key in ("val/r_precision_top3", "val/mm_dist", "val/diversity", "val/action_accuracy"):
        assert any(r.get(key) for r in rows), f"{key} was not logged"
    kept = list(run.glob("checkpoints/best-fid-*.ckpt"))
    assert len(kept) == 1, kept
    state = torch.load(kept[0], map_location="cpu", weights_only=True)
    best_step = min(fids, key=fids.get)
    print(f"\nlogged FID by step: {fids}; kept {kept[0].name} (global step {state['global_step']})")
    assert state["global_step"] == best_step + 1 or state["global_step"] == best_step
    callback = next(v for k, v in state["callbacks"].items() if "val/fid" in k)
    assert callback["best_model_score"].item() == pytest.approx(min(fids.values()), rel=1e-5)


@pytest.mark.slow
def test_evaluate_writes_paper_table_and_sweep_plot(text_ckpt, tmp_path):
    common = [f"checkpoint={text_ckpt}", "replications=2", "mm_replications=1", "mm_repeats=10", "mm_conditions=4",
              "steps=3", "wandb=false"]  # fmt: skip
    proc = run_cli("evaluate.py", *common, env_dir=tmp_path, process=True)
    run = next((tmp_path / "outputs").glob("evaluate/*"))
    table = (run / "table.md").read_text()
    assert "| Real |" in table and "R-Precision top-3" in table and "MultiModality" in table
    metrics = json.loads((run / "metrics.json").read_text())
    assert metrics["summary"]["fid"][2] == 2 and metrics["summary"]["multimodality"][2] == 1
    assert metrics["real"]["r_precision_top3"][0] > 0.3  # real clips match their captions far above chance (0.1)
    assert {r["method"] for r in csv.DictReader(open(run / "table.csv"))} >= {"Real"}
    # does the motion do the action its caption names: label captions, random captions, the real clips' accuracy
    assert metrics["summary"]["action_accuracy"][2] == 2 and "action_accuracy_random" in metrics["summary"]
    assert metrics["real"]["action_accuracy"][0] > 0.5 and "Action acc. (label caption)" in table
    assert "ratio" in table and "| raise-up-both-hands |" in (run / "action_accuracy.md").read_text()
    assert (run / "action_confusion.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "Real" in proc.stdout

    run_cli("evaluate.py", "-m", "guidance=0,2.5", *common[:1], "replications=2", "mm_replications=0", "steps=3",
            "wandb=false", env_dir=tmp_path)  # fmt: skip
    sweep = next((tmp_path / "outputs").glob("evaluate_multirun/*"))
    png = sweep / "guidance_sweep.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in sweep.glob("guidance=*")) == ["guidance=0", "guidance=2.5"]
    assert "| 2.5 |" in (sweep / "guidance_sweep.md").read_text()


def test_evaluate_refuses_a_checkpoint_of_another_dataset(text_ckpt, tmp_path):
    assert "pass dataset=bandai_mini" in user_error("evaluate", tmp_path, f"checkpoint={text_ckpt}", "dataset=kit",
                                                     "wandb=false")  # fmt: skip


def test_evaluation_off_alone_trains_without_a_best_fid_checkpoint(tmp_path, caplog):
    """``callbacks.evaluation=null`` is enough: the best-FID checkpoint (which nothing would feed) goes with it."""
    caplog.set_level("INFO", logger="motiondiff.cli.train")
    _, run = run_entry("train", tmp_path, *TINY, "trainer.max_steps=8", "trainer.check_val_every_n_epoch=1",
                       "checkpoint_every=100", "callbacks.evaluation=null")  # fmt: skip
    assert (run / "checkpoints" / "last.ckpt").is_file() and not list(run.glob("checkpoints/best-fid-*"))
    assert "no best-FID checkpoint either" in caplog.text


def test_unconstrained_jp_model_with_smoothing_reports_its_own_feature_smoothness(tmp_path):
    """vvMDM's setting on the embedded data: an unconditioned jp model, the Gaussian filter in evaluation and the
    smoothness of its own (joint-position) features beside the HumanML3D-bridge one (evaluate.py's report, in-process
    with an untrained tiny model: the columns, not the numbers, are under test)."""
    from fixtures.tiny_models import tiny_datamodule, tiny_module
    from hydra import compose, initialize_config_dir

    from motiondiff.cli.evaluation import report_evaluation
    from motiondiff.runtime.paths import CONF_DIR

    dm = tiny_datamodule(representation="jp")
    module = tiny_module(dm, ("condition=none", "representation=jp"))
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        cfg = compose("evaluate", overrides=["replications=1", "mm_replications=0", "steps=2", "wandb=false",
                                             "smooth_sigma=2", "precision=32-true"])  # fmt: skip
    report_evaluation(cfg, module, dm, tmp_path, "tiny jp model")
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    assert metrics["smooth_sigma"] == 2 and "smoothness_own" in metrics["summary"]
    assert (
        0 < metrics["real"]["smoothness_own"][0] <= 1
        and "Smoothness (own features)" in (tmp_path / "table.md").read_text()
    )
    table = (tmp_path / "table.md").read_text()  # an unconditioned model is sampled with neither guidance nor pools
    assert "guidance none (unconditioned)" in table and "R-precision pools" not in table
