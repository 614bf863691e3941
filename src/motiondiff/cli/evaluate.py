"""`python evaluate.py ...`: a checkpoint's metrics over N replications, beside the Real row, as the papers report
(the protocol: `motiondiff.cli.evaluation`). Outputs: table.md, table.csv, metrics.json (read by the guidance sweep
plot) and an offline W&B run whose summary holds the table.
"""

from __future__ import annotations

from pathlib import Path

from hydra.core.hydra_config import HydraConfig
from hydra.utils import instantiate
from omegaconf import DictConfig

from motiondiff.cli.common import find_model
from motiondiff.cli.evaluation import check_settings, report_evaluation
from motiondiff.cli.validate import RULES_EVALUATE, check
from motiondiff.lit.generation import feed_forward_shape
from motiondiff.model_files.loading import load_model as load_module
from motiondiff.pipelines.coverage import load_prompt_mapping
from motiondiff.runtime.hardware import inference_precision, resolve_device


def run(cfg: DictConfig) -> Path:
    check(cfg, RULES_EVALUATE)  # types and ranges before any work
    cfg.device = resolve_device(cfg.device)  # auto: the GPU where there is one

    out = Path(HydraConfig.get().runtime.output_dir)
    ckpt = find_model(cfg.checkpoint, cfg.paths.output_dir)
    module = load_module(ckpt, cfg.device)
    check_settings(cfg, module)  # before any work: bad settings fail at once
    if module.condition_kind == "text":
        module.prompt_mapping = load_prompt_mapping(ckpt, cfg.prompt_mapping)
    shape = feed_forward_shape(module, int(cfg.batch_size), int(module.hparams.max_frames))
    cfg.precision = inference_precision(cfg.precision, cfg.device, shape)  # auto: bf16 where measured faster
    rep = (module.hparams.get("representation") or {}).get("name")
    overrides = {"representation": rep} if rep else {}
    if module.hparams.get("max_frames"):  # clips cropped as the model trained (it never made longer motion)
        overrides["max_frames"] = int(module.hparams.max_frames)
    dm = instantiate(cfg.dataset.datamodule, **overrides)
    report_evaluation(cfg, module, dm, out, str(ckpt))
    return out
