"""`python -m motiondiff.cli.train_evaluator dataset=...`: train and release a dataset's evaluators.

Trains the text-motion matching evaluator (if the dataset has captions) and the action classifier (if it has
labels) on the train split, keeps the best validation epoch, checks them on the test split and writes
`<out_dir>/{text_motion,action}.{safetensors,json}`. The JSON holds the architecture, the vocabulary and the
provenance: dataset, epochs, the validation score and the test checks printed at the end.
"""

from __future__ import annotations

import logging
import subprocess
import time
from pathlib import Path

import lightning as L
import numpy as np
import torch
from hydra.utils import instantiate
from omegaconf import DictConfig, OmegaConf

from motiondiff import metrics as M
from motiondiff.cli.common import REPO_DIR, UsageError
from motiondiff.cli.validate import check_finite
from motiondiff.data.datamodules import MotionDataModule
from motiondiff.eval.protocol import TEXT_MOTION, EvalClips, Evaluators, time_reversed
from motiondiff.lit.evaluator import ActionClassifierModule, MovementAutoencoderModule, TextMotionEvaluatorModule
from motiondiff.model_files.evaluators import save_released
from motiondiff.models.evaluators.networks import ActionClassifierGRU, TextMotionEvaluator
from motiondiff.text.word_vectors import Vocabulary, load_glove

log = logging.getLogger(__name__)


def _git_commit() -> str:
    try:
        out = subprocess.run(["git", "rev-parse", "HEAD"], cwd=REPO_DIR, capture_output=True, text=True, check=True)
        return out.stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def _fit(cfg: DictConfig, module: L.LightningModule, dm: MotionDataModule, epochs: int) -> float:
    trainer = L.Trainer(**OmegaConf.to_container(cfg.trainer, resolve=True), max_epochs=epochs, logger=False,
                        default_root_dir=str(Path.cwd()))  # fmt: skip
    start = time.perf_counter()
    trainer.fit(module, datamodule=dm)
    if module.best_state is None:
        raise UsageError("the evaluator was never validated: train for at least trainer.check_val_every_n_epoch epochs")
    return time.perf_counter() - start


def train_text_motion(cfg: DictConfig, dm: MotionDataModule) -> TextMotionEvaluator:
    c = cfg.evaluator_model.text_motion
    captions = [t for rec in dm.dataset("train").records for t in rec.texts]
    if c.glove_dir:
        vocab, vectors = load_glove(c.glove_dir)
        words, word_dim, learned = vocab.words, vectors.shape[1], False
    else:
        words, word_dim, learned = Vocabulary.from_captions(captions).words, c.word_dim, True
    evaluator = TextMotionEvaluator(
        dm.feature_dim, words, word_dim=word_dim, movement_hidden=c.movement_hidden, movement_size=c.movement_size,
        text_hidden=c.text_hidden, motion_hidden=c.motion_hidden, output_size=c.output_size,
        unit_length=4, learned_words=learned,
    )  # fmt: skip
    if not learned:
        evaluator.word_vectors.weight.data.copy_(torch.from_numpy(vectors))
    seconds = 0.0
    if c.movement_epochs > 0:  # stage 1: the movement encoder as an autoencoder (official recipe)
        stage1 = MovementAutoencoderModule(evaluator, dm.mean, dm.std, lr=c.lr, wd=c.weight_decay)
        seconds += _fit(cfg, stage1, dm, c.movement_epochs)
        evaluator.movement_encoder.load_state_dict(stage1.best_state)
    module = TextMotionEvaluatorModule(evaluator, dm.mean, dm.std, lr=c.lr, wd=c.weight_decay,
                                       freeze_movement=c.movement_epochs > 0, summary_weight=c.summary_weight)  # fmt: skip
    seconds += _fit(cfg, module, dm, c.epochs)
    evaluator.load_state_dict(module.best_state)
    evaluator.train_info = {"epochs": c.epochs, "best_epoch": module.best_epoch, "seconds": round(seconds, 1),
                            "val_r_precision_top3": module.best_score}  # fmt: skip
    return evaluator.eval()


def train_action(cfg: DictConfig, dm: MotionDataModule) -> ActionClassifierGRU:
    c = cfg.evaluator_model.action
    classifier = ActionClassifierGRU(dm.num_joints * 3, c.hidden_size, c.num_layers, len(dm.action_names),
                                     c.feature_size, input_kind=c.input)  # fmt: skip
    module = ActionClassifierModule(classifier, dm.mean, dm.std, dm.num_joints, lr=c.lr, wd=c.weight_decay,
                                    crop_min=c.crop_min, mirror=c.mirror, action_names=list(dm.action_names),
                                    select_by=c.get("select_by", "accuracy"))  # fmt: skip
    seconds = _fit(cfg, module, dm, c.epochs)
    classifier.load_state_dict(module.best_state)
    classifier.train_info = {"epochs": c.epochs, "best_epoch": module.best_epoch, "seconds": round(seconds, 1),
                             "selected_by": f"val {module.hparams.select_by}", "class_balance": dm.balance,
                             **{f"val_{k}": v for k, v in module.best_scores.items()}}  # fmt: skip
    return classifier.eval()


def test_checks(
    evaluators: Evaluators, dm: MotionDataModule, replications: int = 20, seed: int = 0, split: str = "test"
) -> dict:
    """The sanity checks of a released evaluator on real clips of a split (no generated motion involved); on val
    they are what sizes are chosen by, on test they are reported."""
    test = EvalClips.from_dataset(dm.dataset(split))
    train = EvalClips.from_dataset(dm.dataset("train"))
    real_test, real_train = evaluators.embed_motion(test.features), evaluators.embed_motion(train.features)
    out: dict = {f"{split}_clips": len(test)}
    if evaluators.text_motion is not None:
        reversed_test = evaluators.embed_motion([time_reversed(f, dm.num_joints) for f in test.features])
        rng = np.random.default_rng(seed)
        tops = [M.r_precision(evaluators.embed_text(test.pick_captions(rng)), real_test[TEXT_MOTION])
                for _ in range(replications)]  # fmt: skip
        for k in ("top1", "top2", "top3"):
            out[f"r_precision_{k}"] = float(np.mean([t[k] for t in tops]))
        stats = {name: M.gaussian_statistics(e[TEXT_MOTION])
                 for name, e in (("test", real_test), ("train", real_train), ("reversed", reversed_test))}  # fmt: skip
        out[f"fid_{split}_vs_train"] = M.frechet_distance(*stats["test"], *stats["train"])
        out[f"fid_{split}_vs_reversed"] = M.frechet_distance(*stats["test"], *stats["reversed"])
    if evaluators.action is not None:
        predicted = real_test["action_logits"].argmax(-1)
        out["accuracy"] = float((predicted == test.actions).mean())
        # mean per-action recall over the actions the split holds: the rare actions weigh as much as the common ones
        out["balanced_accuracy"] = float(np.mean([(predicted[test.actions == a] == a).mean()
                                                  for a in np.unique(test.actions)]))  # fmt: skip
        stats = [M.gaussian_statistics(e["action_features"]) for e in (real_test, real_train)]
        out[f"action_fid_{split}_vs_train"] = M.frechet_distance(*stats[0], *stats[1])
    return out


def _overrides(cfg: DictConfig) -> list[str]:
    """The command line's overrides (so the release records how it was trained), or the dataset and size."""
    try:
        from hydra.core.hydra_config import HydraConfig

        return list(HydraConfig.get().overrides.task)
    except ValueError:  # not run through Hydra
        return [f"dataset={cfg.dataset.name}", f"evaluator_model={cfg.evaluator_model.name}"]


def run(cfg: DictConfig) -> Path:

    check_finite(cfg)  # a NaN or infinite setting fails before any work
    L.seed_everything(cfg.seed, workers=True)
    dm: MotionDataModule = instantiate(cfg.dataset.datamodule)
    dm.setup(None)
    records = dm.dataset("train").records
    has_text = any(r.texts for r in records)
    has_action = bool(getattr(dm, "action_names", None)) and any(r.action >= 0 for r in records)
    which = [w for w in cfg.which if (w == "text_motion" and has_text) or (w == "action" and has_action)]
    unknown = set(cfg.which) - {"text_motion", "action"}
    if unknown or not which:
        raise UsageError(
            f"nothing to train for which={list(cfg.which)} on {cfg.dataset.name} (captions: {has_text}, "
            f"labels: {has_action}); which takes text_motion and/or action"
        )
    models = {}
    if "text_motion" in which:
        models["text_motion"] = train_text_motion(cfg, dm)
    if "action" in which:
        models["action"] = train_action(cfg, dm)
    evaluators = Evaluators(models.get("text_motion"), models.get("action"), dm.num_joints)
    checks = test_checks(evaluators, dm, seed=cfg.seed)
    val_checks = test_checks(evaluators, dm, seed=cfg.seed, split="val")
    out = Path(cfg.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    command = "python -m motiondiff.cli.train_evaluator " + " ".join(_overrides(cfg))
    for kind, model in models.items():
        meta = {
            "dataset": cfg.dataset.name,
            "feature_dim": dm.feature_dim,
            "num_joints": dm.num_joints,
            "action_names": list(getattr(dm, "action_names", []) or []) if kind == "action" else None,
            "training": model.train_info,
            "test_checks": checks,
            "val_checks": val_checks,
            "command": command,
            "git_commit": _git_commit(),
        }
        save_released(model, out / kind, meta)
    print(f"\nevaluators written to {out}")
    for split, values in (("val", val_checks), ("test", checks)):
        for k, v in values.items():
            print(f"  {split:>4} {k:>26}: {v:.4g}" if isinstance(v, float) else f"  {split:>4} {k:>26}: {v}")
    return out


# python -m motiondiff.cli.train_evaluator dataset=<name> [evaluator_model=paper] [which=[...]]
if __name__ == "__main__":
    from motiondiff.runtime.scripting import run_hydra

    run_hydra("train_evaluator", run)
