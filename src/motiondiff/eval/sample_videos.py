"""Generated motion in the training dashboards: a few fixed samples as animated GIFs at each in-training evaluation.

Scalars alone do not show what a model generates. `SampleVideos` samples the same conditions every time (prompts
for text models, action names for action models, nothing for unconditioned ones) with a fixed seed and a few DDIM
steps, so successive evaluations differ only by the weights; renders each as a small GIF with the project's
renderer (`export.render.render_motion`) into `<run>/videos/step<N>/`; and logs them to every active logger:
W&B as `wandb.Video` of the file (no moviepy needed), TensorBoard as an image summary holding the GIF bytes (its
Images tab plays them). The CSV log keeps scalars only; the GIF files stay in the run folder for it.
"""

from __future__ import annotations

import io
import logging
import re
from dataclasses import dataclass, field
from pathlib import Path

import torch

from motiondiff.edit.smoothing import smooth_joints
from motiondiff.export.render import check_video_size, render_motion
from motiondiff.lit.generation import fitted_steps, generate_features
from motiondiff.runtime.errors import UsageError

log = logging.getLogger(__name__)
KEY = "callbacks.evaluation.videos"
TAG = "samples"  # the dashboards' section: samples/<k>_<condition>
MAX_VIDEOS = 8
LIMITS = {"count": (1, MAX_VIDEOS), "seconds": (0.1, 60), "steps": (1, 1000), "frame_step": (1, 100)}


@dataclass
class SampleVideos:
    """What to sample and how to render it (``callbacks.evaluation.videos`` in conf/callbacks/default.yaml)."""

    prompts: list[str] = field(default_factory=lambda: ["a person walks forward", "a person raises both hands"])
    actions: list[str] | None = None  # action models; None: the model's first `count` actions
    count: int = 2  # unconditioned models (and actions=None): how many motions
    seconds: float = 3.0
    steps: int = 10  # DDIM steps (at most the model's diffusion steps)
    size: int = 160  # pixels square: small, as every evaluation logs them
    frame_step: int = 3  # every 3rd frame
    seed: int = 0  # the evaluation's seed

    def __post_init__(self):
        for key, (low, high) in LIMITS.items():
            value = getattr(self, key)
            whole = key != "seconds"
            kind = int if whole else int | float
            if isinstance(value, bool) or not isinstance(value, kind) or not low <= value <= high:
                raise UsageError(f"{KEY}.{key}={value!r}: must be {'an integer' if whole else 'a number'} from {low:g}"
                                 f" to {high:g}; fix it with {KEY}.{key}=<value>")  # fmt: skip
        check_video_size(self.size, f"{KEY}.size")  # the rule of the commands' video.size

    @classmethod
    def from_config(cls, cfg, seed: int = 0) -> SampleVideos | None:
        """From the callback's ``videos`` mapping (a DictConfig or dict); None or empty: no videos."""
        if not cfg:
            return None
        from omegaconf import DictConfig, OmegaConf

        values = OmegaConf.to_container(cfg, resolve=True) if isinstance(cfg, DictConfig) else dict(cfg)
        for key in ("prompts", "actions"):
            if isinstance(values.get(key), str):  # videos.prompts="a person waves": one prompt
                values[key] = [values[key]]
        settings = [k for k in cls.__dataclass_fields__ if k != "seed"]
        unknown = sorted(set(values) - set(settings))
        if unknown:
            raise UsageError(f"{KEY}.{unknown[0]} is not a setting; the settings are {', '.join(settings)}")
        return cls(**values, seed=int(seed))

    def conditions(self, module) -> list:
        """The conditions to sample for this model; UsageError (naming the key to fix) when they do not fit it."""
        kind = module.condition_kind
        if kind == "text":
            prompts = list(self.prompts or [])
            if not 0 < len(prompts) <= MAX_VIDEOS or not all(isinstance(p, str) and p.strip() for p in prompts):
                raise UsageError(f"{KEY}.prompts must list 1 to {MAX_VIDEOS} texts, got {self.prompts!r}; e.g. "
                                 f"'{KEY}.prompts=[a person walks forward]' (or {KEY}=null for no videos)")  # fmt: skip
            return prompts
        if kind == "action":
            names = list(module.hparams.action_names or [])
            chosen = list(self.actions) if self.actions else names[: self.count]
            if len(chosen) > MAX_VIDEOS:
                raise UsageError(f"{KEY}.actions: at most {MAX_VIDEOS} actions, got {len(chosen)}")
            unknown = [a for a in chosen if a not in names]
            if unknown:
                raise UsageError(f"{KEY}.actions: this model has no action {unknown[0]!r}; its actions are "
                                 f"{', '.join(names)}")  # fmt: skip
            return chosen
        return [None] * self.count

    def log(self, trainer, module, guidance: float, precision: str = "32-true") -> list[tuple[str, Path, str]]:
        """Sample, render into ``<default_root_dir>/videos/step<N>/`` and log to ``trainer.loggers``."""
        step = int(trainer.global_step)
        videos = self.render(module, Path(trainer.default_root_dir) / "videos" / f"step{step:07d}", guidance,
                             precision)  # fmt: skip
        log_videos(trainer.loggers, videos, step)
        log.info("sample videos at step %d: %s", step, videos[0][1].parent if videos else "none")
        return videos

    def render(self, module, folder: Path, guidance: float, precision: str = "32-true") -> list[tuple[str, Path, str]]:
        """(tag, GIF path, caption) per condition: sampled with the seed, ``steps`` DDIM steps and the model's
        smoothing, rendered into ``folder``."""

        conditions = self.conditions(module)
        fps = float(module.hparams.fps)
        frames = max(2, min(round(self.seconds * fps), int(module.hparams.max_frames)))
        generator = torch.Generator(device=module.device).manual_seed(self.seed)
        steps = fitted_steps(module, None, self.steps)  # capped at a few-step model's T
        feats = generate_features(module, conditions, torch.full((len(conditions),), frames), generator=generator,
                                  precision=precision, sampler="ddim", steps=steps, guidance=guidance)  # fmt: skip
        folder.mkdir(parents=True, exist_ok=True)
        rep, sigma = module.representation, module.default_smooth_sigma
        videos = []
        for k, (condition, f) in enumerate(zip(conditions, feats, strict=True)):
            joints = smooth_joints(rep.decode_numpy(f), sigma)
            tag = f"{TAG}/{k}_{slug(condition)}"
            path = render_motion(joints, rep.skeleton, folder / f"{k}_{slug(condition)}.gif", fps=fps, size=self.size,
                                 frame_step=self.frame_step)  # fmt: skip
            videos.append((tag, path, "unconditioned" if condition is None else str(condition)))
        return videos


def slug(condition) -> str:
    """A tag- and file-safe name of a condition: "a person walks" -> a_person_walks; None -> unconditioned."""
    if condition is None:
        return "unconditioned"
    return re.sub(r"[^a-z0-9]+", "_", str(condition).lower()).strip("_")[:48] or "condition"


def log_videos(loggers, videos: list[tuple[str, Path, str]], step: int) -> None:
    """Log (tag, GIF path, caption) triples to each logger that shows video: W&B (one history row) and TensorBoard."""
    from lightning.pytorch.loggers import TensorBoardLogger, WandbLogger

    for logger in loggers:
        if isinstance(logger, WandbLogger):
            import wandb

            logger.log_metrics({tag: wandb.Video(str(path), caption=caption, format="gif")
                                for tag, path, caption in videos}, step=step)  # fmt: skip
        elif isinstance(logger, TensorBoardLogger):
            writer = logger.experiment
            for tag, path, _ in videos:
                add_gif(writer, tag, path, step)
            writer.flush()


def gif_summary(tag: str, gif: bytes):
    """A TensorBoard ``Summary`` whose image is the GIF itself (TensorBoard serves an image summary's bytes as they
    are, so an animated GIF plays in its Images tab; ``SummaryWriter.add_image`` would re-encode one frame as PNG)."""
    from PIL import Image
    from tensorboard.compat.proto.summary_pb2 import Summary

    with Image.open(io.BytesIO(gif)) as image:
        if image.format != "GIF":
            raise ValueError(f"{tag}: expected GIF bytes, got {image.format}")
        width, height = image.size
        channels = 4 if "transparency" in image.info else 3  # RGBA or RGB (informative: the bytes are served as is)
    encoded = Summary.Image(height=height, width=width, colorspace=channels, encoded_image_string=gif)
    return Summary(value=[Summary.Value(tag=tag, image=encoded)])


def add_gif(writer, tag: str, path: str | Path, step: int) -> None:
    """Write the GIF at ``path`` to a ``torch.utils.tensorboard.SummaryWriter`` (Lightning's TensorBoardLogger's
    writer when the tensorboard package is installed) as the image ``tag`` at ``step``."""
    writer._get_file_writer().add_summary(gif_summary(tag, Path(path).read_bytes()), global_step=int(step))
