"""`python evaluate.py evaluator=official official_dir=<MDM's layout>` runs end to end for KIT (text-motion
evaluator), HumanAct12 (the real action-to-motion classifier on 24 joints) and UESTC (ST-GCN, FID against train and
test), each on a tiny model trained by train.py on a fixture in the dataset's official layout. The commands' configs and
runs are called in-process (`fixtures.in_process`; a subprocess adds 9 s of imports and nothing these tests check)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from cli_helpers import TINY, write_kit_layout
from fixtures.in_process import run_entry
from fixtures.official_layouts import write_official_action, write_official_t2m

FAST_EVAL = ["replications=1", "mm_replications=0", "sampler=ddim", "steps=2", "wandb=false", "batch_size=16"]


def _train(tmp_path, *overrides) -> str:
    _, run = run_entry("train", tmp_path / "train", *TINY, "trainer.max_steps=2", "checkpoint_every=2", *overrides)
    return str(run / "checkpoints" / "last.ckpt")


def _evaluate(tmp_path, *overrides) -> tuple[dict, str]:
    """metrics.json and table.md of an evaluate.py run."""
    _, out = run_entry("evaluate", tmp_path / "evaluate", *overrides, *FAST_EVAL)
    return json.loads((out / "metrics.json").read_text()), (out / "table.md").read_text()


@pytest.mark.slow
@pytest.mark.shared
def test_kit_with_the_official_text_motion_evaluator(shared, tmp_path):
    root = write_kit_layout(tmp_path / "KIT-ML")
    official = tmp_path / "official"
    write_official_t2m(official, shared("reference", "t2m_evaluator_state_dict_layout.txt").read_text(), "kit", 251)
    ckpt = _train(tmp_path, "dataset=kit", f"dataset.root={root}")
    summary, table = _evaluate(tmp_path, f"checkpoint={ckpt}", "dataset=kit", f"dataset.root={root}",
                               "evaluator=official", f"official_dir={official}")  # fmt: skip
    assert "R-Precision top-3" in table and np.isfinite(summary["summary"]["fid"][0])


@pytest.mark.slow
@pytest.mark.shared
@pytest.mark.parametrize("dataset", ["humanact12", "uestc"])
def test_action_datasets_with_the_official_classifiers(shared, tmp_path, dataset):
    from fixtures.action_layouts import write_humanact12_fixture, write_uestc_fixture

    root = tmp_path / dataset
    (write_humanact12_fixture if dataset == "humanact12" else write_uestc_fixture)(root)
    official = tmp_path / "official"
    write_official_action(official, shared("reference", "action-recognition"))
    ckpt = _train(tmp_path, f"dataset={dataset}", f"dataset.root={root}", "condition=action")
    results, table = _evaluate(tmp_path, f"checkpoint={ckpt}", f"dataset={dataset}", f"dataset.root={root}",
                               "evaluator=official", f"official_dir={official}")  # fmt: skip
    metrics = results["summary"]
    for key in ("fid", "accuracy", "diversity"):
        assert np.isfinite(metrics[key][0]), key
    # UESTC's test subjects are not its train subjects: MDM Table 4 reports FID against both. HumanAct12 trains on
    # every clip and is evaluated against them, so there is one FID.
    assert ("FID (train)" in table) == (dataset == "uestc") and ("fid_train" in metrics) == (dataset == "uestc")


def test_official_without_a_folder_names_the_layout(text_ckpt):
    from omegaconf import OmegaConf

    from motiondiff.cli.evaluation import load_evaluators
    from motiondiff.model_files.loading import load_model
    from motiondiff.runtime.errors import UsageError

    cfg = OmegaConf.create({"evaluator": "official", "official_dir": None, "dataset": {"name": "bandai_mini"}})
    with pytest.raises(UsageError, match="official_dir=<folder>") as err:
        load_evaluators(cfg, load_model(text_ckpt), None)
    assert "finest.tar" in str(err.value)
