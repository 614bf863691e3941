"""MDM Tab. 6 trains with T = 10 diffusion steps: its in-training evaluation and evaluate.py must sample with what
fits T (the default DDIM-50 cannot run on a 10-step process), and an explicit steps= above T is one clear error."""

from __future__ import annotations

import csv
import json

import pytest
from cli_helpers import REPO, TINY, run_cli
from fixtures.in_process import run_entry

EVALUATORS = REPO / "checkpoints" / "evaluators" / "bandai_mini"
# the paper preset itself, on the embedded data with its text encoder and the CPU trainer (HumanML3D and CLIP are
# what users bring): the diffusion process and the evaluation callback are the preset's
ON_EMBEDDED_DATA = ["experiment=mdm_humanml3d_tab6_t10", "dataset=bandai_mini", "text_encoder=minilm", "model=cpu",
                    "trainer=cpu", "batch_size=16", "optim.lr=1e-3"]  # 16 steps an epoch  # fmt: skip

pytestmark = pytest.mark.skipif(
    not (EVALUATORS / "text_motion.safetensors").is_file(),
    reason=f"no shipped evaluators in {EVALUATORS}: rebuild them with python -m motiondiff.cli.train_evaluator",
)


@pytest.mark.slow
def test_t10_preset_trains_evaluates_and_samples(tmp_path):
    run_cli("train.py", *ON_EMBEDDED_DATA, *TINY, "trainer.max_steps=16", "trainer.check_val_every_n_epoch=1",
            "checkpoint_every=100", "callbacks.evaluation.num_clips=8", env_dir=tmp_path)  # fmt: skip
    run = next((tmp_path / "outputs").glob("train/*"))
    rows = list(csv.DictReader(open(next(run.glob("csv/version_*/metrics.csv")))))
    assert any(r.get("val/fid") for r in rows), "the in-training evaluation logged no FID"
    ckpt = run / "checkpoints" / "last.ckpt"

    # evaluate.py and sample.py in-process (their command lines are tested elsewhere; a subprocess adds 9 s each)
    _, out = run_entry("evaluate", tmp_path / "evaluate", f"checkpoint={ckpt}", "dataset=bandai_mini",
                       "replications=1", "mm_replications=0", "wandb=false")  # fmt: skip
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["steps"] == 10 and metrics["summary"]["fid"][0] > 0  # DDIM over the whole 10-step chain

    _, out = run_entry("sample", tmp_path / "sample", f"checkpoint={ckpt}", "text=a person walks", "num_samples=1",
                       "export=none", "sampler=ddim")  # DDIM's default 50 steps, fitted to T  # fmt: skip
    assert json.loads((out / "results.json").read_text())["steps"] == 10
    _, out = run_entry("sample", tmp_path / "sample_default", f"checkpoint={ckpt}", "text=a person walks",
                       "num_samples=1", "export=none")  # the default sampler, DPM-Solver++-7, fits in T  # fmt: skip
    summary = json.loads((out / "results.json").read_text())
    assert summary["steps"] == 7 and summary["sampler"]["name"] == "dpmpp"
    from omegaconf import OmegaConf

    from motiondiff.cli.common import sampling_steps
    from motiondiff.model_files.loading import load_model
    from motiondiff.runtime.errors import UsageError

    with pytest.raises(UsageError, match="between 1 and the model's 10 diffusion steps"):  # what sample.py checks
        sampling_steps(OmegaConf.create({"steps": 50, "sampler": {"steps": 50}}), load_model(ckpt))
