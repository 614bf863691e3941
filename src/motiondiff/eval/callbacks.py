"""Evaluation while training: generate for a fixed validation subset, compute the protocol's metrics, log them.

`GenerationEvaluation` runs at the end of every N-th validation epoch. It samples one motion per clip of a fixed
subset of the validation split (fast DDIM sampling, fixed seed, so evaluations differ only by the weights), embeds
them with the dataset's evaluators and logs `val/fid`, `val/r_precision_top{1,2,3}`, `val/mm_dist`,
`val/diversity` (text), `val/accuracy` (action) or `val/kid`, `val/precision`, `val/recall` (unconditioned).
Text models on labelled data also sample once from each clip's label caption and log `val/action_accuracy` (does
the motion do the action its caption names, by the dataset's action classifier).
With `videos` set, each evaluation also logs a few generated motions as GIFs to the dashboards (W&B, TensorBoard;
motiondiff.eval.sample_videos).
A `ModelCheckpoint(monitor="val/fid", mode="min", save_top_k=1)` placed after it keeps the best-FID checkpoint
(`callbacks.best_fid.monitor=val/action_accuracy callbacks.best_fid.mode=max` keeps the best action accuracy).

Weights that generate NaN or infinite motion (a diverged run) are logged as the worst scores (`val/fid=inf`, zero
accuracies) rather than stopping the training, so the best-FID checkpoint never picks them.

Place it before `EMAWeightAveraging` in the callback list: that callback swaps the averaged weights back out in
its own `on_validation_epoch_end`, and the evaluation should see the averaged weights the model is sampled with.
"""

from __future__ import annotations

import logging
import time
from pathlib import Path

import lightning as L
import numpy as np
import torch
from tqdm import tqdm

from motiondiff.eval.protocol import EvalClips, Evaluators, action_accuracy, generate, replication_metrics
from motiondiff.eval.sample_videos import SampleVideos
from motiondiff.lit.generation import NonFiniteOutput

log = logging.getLogger(__name__)


class GenerationEvaluation(L.Callback):
    def __init__(
        self,
        evaluator_dir: str | Path,
        every_n_epochs: int = 1,
        num_clips: int = 32,
        split: str = "val",
        sampler: str = "ddim",
        steps: int = 50,
        guidance: float | None = None,
        batch_size: int = 64,
        seed: int = 0,
        precision: str = "32-true",
        action_accuracy: bool = True,
        videos: dict | None = None,
    ):
        self.evaluator_dir = Path(evaluator_dir)
        self.every_n_epochs = every_n_epochs
        self.num_clips, self.split = num_clips, split
        self.sampling = {"sampler": sampler, "steps": steps, "precision": precision}
        self.guidance, self.batch_size, self.seed = guidance, batch_size, seed
        self.action_accuracy = action_accuracy
        self.videos = SampleVideos.from_config(videos, seed)  # None: no sample videos
        self.evaluators: Evaluators | None = None
        self._real: tuple[EvalClips, dict, list] | None = None

    @property
    def available(self) -> bool:
        """Whether the dataset has evaluators (without them there is nothing to compute and no val/fid)."""
        return any((self.evaluator_dir / f"{k}.safetensors").is_file() for k in ("text_motion", "action"))

    def setup(self, trainer: L.Trainer, pl_module: L.LightningModule, stage: str) -> None:
        num_steps = int(pl_module.diffusion.num_steps)
        if self.sampling["steps"] is not None and self.sampling["steps"] > num_steps:  # e.g. MDM Tab. 6, T = 10
            log.info("evaluation samples with %s over all %d diffusion steps (asked %d)", self.sampling["sampler"],
                     num_steps, self.sampling["steps"])  # fmt: skip
            self.sampling["steps"] = num_steps
        if self.videos is not None and self.available:
            self.videos.conditions(pl_module)  # prompts or action names that do not fit the model fail before training
        if self.available and self.evaluators is None:
            self.evaluators = Evaluators.load(self.evaluator_dir, num_joints=pl_module.hparams.num_joints)
            self.evaluators.for_module(pl_module)

    def _real_set(self, trainer: L.Trainer, pl_module) -> tuple[EvalClips, dict, list]:
        if self._real is None:
            clips = EvalClips.from_dataset(trainer.datamodule.dataset(self.split), self.num_clips, self.seed)
            captions = clips.pick_captions(np.random.default_rng(self.seed))
            self._real = (clips, self.evaluators.embed_motion(clips.features), captions)
        return self._real

    def on_validation_epoch_end(self, trainer: L.Trainer, pl_module) -> None:
        if self.evaluators is None or trainer.sanity_checking:
            return
        if (trainer.current_epoch + 1) % self.every_n_epochs:
            return
        start = time.perf_counter()
        was_training = pl_module.training
        try:
            values = self._metrics(trainer, pl_module)
        except NonFiniteOutput:
            values = self.worst_scores(pl_module.condition_kind)
            log.warning("evaluation at step %d: the model generated NaN or infinite motion; logged val/fid=inf",
                        trainer.global_step)  # fmt: skip
        pl_module.train(was_training)
        for name, value in values.items():
            pl_module.log(f"val/{name}", float(value), prog_bar=name == "fid", sync_dist=True)
        log.info("evaluation at step %d (%.1f s): %s", trainer.global_step, time.perf_counter() - start,
                 ", ".join(f"{k} {v:.3f}" for k, v in values.items()))  # fmt: skip

    def worst_scores(self, kind: str) -> dict[str, float]:
        """What a model that generates no finite motion scores: the worst FID and distances, zero accuracies."""
        worst = {"fid": float("inf")}
        if kind == "text":
            worst.update({f"r_precision_top{k}": 0.0 for k in (1, 2, 3)}, mm_dist=float("inf"))
            if self.action_accuracy:
                worst["action_accuracy"] = 0.0
        elif kind == "action":
            worst["accuracy"] = 0.0
        else:
            worst.update(kid=float("inf"), precision=0.0, recall=0.0)
        return worst

    def _metrics(self, trainer: L.Trainer, pl_module) -> dict:
        clips, real, captions = self._real_set(trainer, pl_module)
        kind = pl_module.condition_kind
        conditions = {"text": captions, "action": list(clips.actions)}.get(kind, [None] * len(clips))
        guidance = pl_module.default_guidance if self.guidance is None else self.guidance
        generator = torch.Generator(device=pl_module.device).manual_seed(self.seed)
        labelled_too = self.action_accuracy and self.evaluators.measures_action(kind, clips)
        with tqdm(total=len(clips) * (2 if labelled_too else 1), desc=f"evaluation at step {trainer.global_step}",
                  unit="motion", leave=False, disable=not trainer.is_global_zero) as bar:  # fmt: skip
            feats = generate(pl_module, conditions, clips.lengths, self.batch_size, generator, bar,
                             guidance=guidance, **self.sampling)  # fmt: skip
            labelled = None
            if labelled_too:
                generator.manual_seed(self.seed)
                labelled = generate(pl_module, clips.label_captions(), clips.lengths, self.batch_size, generator, bar,
                                    guidance=guidance, **self.sampling)  # fmt: skip
        gen = self.evaluators.embed_motion(feats)
        feats = self.evaluators.as_hml(feats)  # smoothness in the evaluators' feature space, as every metric
        text = self.evaluators.embed_text(captions) if kind == "text" else None
        values = replication_metrics(kind, self.evaluators, real, gen, text=text, actions=clips.actions,
                                     generated_features=feats, seed=self.seed)  # fmt: skip
        if labelled is not None:
            values["action_accuracy"] = action_accuracy(self.evaluators, self.evaluators.embed_motion(labelled),
                                                        clips.actions)  # fmt: skip
        if self.videos is not None and trainer.is_global_zero:  # rank 0 logs; the others have no loggers to fill
            self.videos.log(trainer, pl_module, guidance, self.sampling["precision"])
        return values
