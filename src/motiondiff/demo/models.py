"""The web demo's models, without any web code (so it is testable on its own).

`DemoModels` offers the released models (text, action, and any other release in checkpoints/models) and, when a
GuidedMotion checkpoint is given, GuidedMotion; each pipeline is loaded on first use and kept, so a page that
generates again (or switches back to a model) does not load it twice. `ModelInfo` is what the page adapts to: the
condition, the length limit, the default guidance, the body parts, the example prompts and whether prompts are
checked against the training captions (the release's coverage bank).
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field
from pathlib import Path

from motiondiff.demo.examples import example_prompts, example_timelines
from motiondiff.demo.files import blender_available
from motiondiff.model_files.resolve import SHIPPED_MODELS, released_names
from motiondiff.pipelines import GuidedMotionPipeline, MotionPipeline
from motiondiff.runtime.errors import UsageError

MAX_SAMPLES = 4  # samples per request: the page shows this many side by side


@dataclass(frozen=True)
class ModelChoice:
    """One entry of the page's model list: ``key`` its value, ``source`` a released name or a checkpoint path."""

    key: str
    label: str
    source: str
    guided: bool = False


@dataclass
class ModelInfo:
    """What the page adapts to for one model."""

    kind: str  # "text", "action" or "guided"
    max_seconds: float
    default_guidance: float
    actions: list[str] = field(default_factory=list)
    parts: list[str] = field(default_factory=list)  # the body-part presets an edit can regenerate (MDM models)
    examples: list[str] = field(default_factory=list)  # example prompts (action names for an action model)
    timelines: list[str] = field(default_factory=list)  # example timelines, one "prompt : seconds" per line
    checks_coverage: bool = False  # a prompt far from the training captions gets a warning


def released_choices() -> list[ModelChoice]:
    """The released models: the "text", "action" and "guidedmotion" aliases first, then other releases in
    checkpoints/models."""
    choices = [ModelChoice(k, f"{k} (released: {p.stem})", k, guided=k == "guidedmotion")
               for k, p in SHIPPED_MODELS.items() if p.is_file()]  # fmt: skip
    aliased = {p.stem for p in SHIPPED_MODELS.values()}
    for name in released_names():  # model releases only (not their .coverage banks)
        if name not in aliased and name not in SHIPPED_MODELS:
            choices.append(ModelChoice(name, f"{name} (released)", name))
    return choices


class DemoModels:
    """The models the demo offers, each loaded once (thread-safe: Gradio runs handlers in worker threads).
    ``blender``: write FBX/GLB (None: where this install has Blender; False: never, e.g. for a fast test)."""

    def __init__(self, guided: str | Path | None = None, local_model: str = "text", device: str = "cpu",
                 blender: bool | None = None):  # fmt: skip
        self.glb = blender_available() if blender is None else bool(blender and blender_available())
        self.choices = released_choices()
        if guided is not None:
            path = Path(guided)
            if not path.is_file():
                raise UsageError(f"no GuidedMotion checkpoint at {path}: give guided=<the .ckpt train_latent.py wrote>")
            self.choices.append(ModelChoice("guided", f"GuidedMotion ({path.name})", str(path), guided=True))
        self.local_model, self.device = local_model, device
        self._loaded: dict[str, MotionPipeline | GuidedMotionPipeline] = {}
        self._lock = threading.Lock()

    def choice(self, key: str) -> ModelChoice:
        for c in self.choices:
            if c.key == key:
                return c
        raise UsageError(f"unknown model {key!r}: choose one of {', '.join(c.key for c in self.choices)}")

    def get(self, key: str) -> MotionPipeline | GuidedMotionPipeline:
        """The pipeline of model ``key``, loaded on the first call and cached."""
        choice = self.choice(key)
        with self._lock:
            if key not in self._loaded:
                if choice.guided:
                    pipe = GuidedMotionPipeline.from_pretrained(choice.source, self.local_model, self.device)
                else:
                    pipe = MotionPipeline.from_pretrained(choice.source, self.device)
                self._loaded[key] = pipe
            return self._loaded[key]

    def mdm(self, key: str, what: str) -> MotionPipeline:
        """The MotionPipeline of ``key`` for ``what`` (an edit, a timeline), or one UsageError for GuidedMotion."""
        pipe = self.get(key)
        if not isinstance(pipe, MotionPipeline):
            raise UsageError(f"{what} needs an MDM model (text or action): choose one in the model list")
        return pipe

    def info(self, key: str) -> ModelInfo:
        pipe = self.get(key)
        examples = example_prompts(pipe)
        if isinstance(pipe, GuidedMotionPipeline):
            decoder = pipe.latent.decoder.hparams
            guidance = float((pipe.latent.hparams.sampling or {}).get("guidance", 7.5))  # the latent model's default
            return ModelInfo("guided", int(decoder.max_frames) / pipe.fps, guidance, examples=examples)
        parts = sorted(pipe.model.representation.skeleton.parts)
        return ModelInfo(pipe.condition_kind, pipe.max_seconds, float(pipe.model.default_guidance), pipe.actions,
                         parts, examples, example_timelines(examples), pipe.coverage is not None)  # fmt: skip
