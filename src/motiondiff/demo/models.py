"""The web demo's models and what one generation writes, without any web code (so it is testable on its own).

`DemoModels` offers the released models (text, action, and any other release in checkpoints/models) and, when a
GuidedMotion checkpoint is given, GuidedMotion; each pipeline is loaded on first use and kept, so a page that
generates again (or switches back to a model) does not load it twice. `generate` runs one request through the public
pipelines (`motiondiff.pipelines`) and writes per sample the files the page shows and offers: the self-contained HTML
viewer, an MP4, a BVH, an NPZ (joints, features and fps in one file) and, where Blender's bpy is available (the
check of export=glb, `export.blender`), a GLB that Blender makes from the BVH. Bad input raises `UsageError`.
"""

from __future__ import annotations

import subprocess
import threading
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from motiondiff.export.blender import blender_command, convert_bvh
from motiondiff.model_files.resolve import SHIPPED_MODELS, released_names
from motiondiff.pipelines import GuidedMotionPipeline, MotionOutput, MotionPipeline
from motiondiff.runtime.errors import UsageError

MAX_SAMPLES = 4  # samples per request: the page has this many result slots
GLB_INCLUDED = "GLB: included (written by Blender from the BVH). BVH, GLB and NPZ are offered."
GLB_MISSING = ("GLB: not available in this install (it needs Blender's bpy: pip install 'motiondiff[blender]', or "
               "MOTIONDIFF_BLENDER_PYTHON naming a Python with bpy or a blender executable). BVH and NPZ are offered.")  # fmt: skip


def glb_available() -> bool:
    """Whether this install can write GLB files: Blender's bpy (or a Blender named by MOTIONDIFF_BLENDER_PYTHON)."""
    return blender_command() is not None


def glb_note(available: bool, failed: str | None = None) -> str:
    """The page's line on GLB downloads: included, missing from this install (and how to get it), or, when Blender
    is there but could not write this request's file (`failed`: its error), that it failed."""
    if not available:
        return GLB_MISSING
    if failed:
        return f"GLB: Blender could not write it this time ({failed}). BVH and NPZ are offered."
    return GLB_INCLUDED


def download_kinds(glb: bool) -> str:
    """The download formats the page names: "BVH, GLB, NPZ" or "BVH, NPZ"."""
    return "BVH, GLB, NPZ" if glb else "BVH, NPZ"


@dataclass(frozen=True)
class ModelChoice:
    """One entry of the page's model list: ``key`` its value, ``source`` a released name or a checkpoint path."""

    key: str
    label: str
    source: str
    guided: bool = False


@dataclass
class ModelInfo:
    """What the page adapts to: the condition ("text", "action" or "guided"), the action names, the length range."""

    kind: str
    max_seconds: float
    default_guidance: float
    actions: list[str] = field(default_factory=list)
    parts: list[str] = field(default_factory=list)  # the body-part presets an edit can regenerate (MDM models)


@dataclass
class Sample:
    """One generated motion's files and its caption line for the page; ``glb`` None where it was not written
    (no Blender, or ``glb_error`` says why Blender failed)."""

    index: int
    title: str
    html: Path
    mp4: Path
    bvh: Path
    npz: Path
    glb: Path | None = None
    glb_error: str | None = None

    def downloads(self) -> list[Path]:
        """The files the page offers for download: the BVH, the GLB when there is one, the NPZ."""
        return [p for p in (self.bvh, self.glb, self.npz) if p is not None]


def released_choices() -> list[ModelChoice]:
    """The released models: the "text" and "action" aliases first, then other releases in checkpoints/models."""
    choices = [ModelChoice(k, f"{k} (released: {p.stem})", k) for k, p in SHIPPED_MODELS.items() if p.is_file()]
    aliased = {p.stem for p in SHIPPED_MODELS.values()}
    for name in released_names():  # model releases only (not their .coverage banks)
        if name not in aliased and name not in SHIPPED_MODELS:
            choices.append(ModelChoice(name, f"{name} (released)", name))
    return choices


class DemoModels:
    """The models the demo offers, each loaded once (thread-safe: Gradio runs handlers in worker threads)."""

    def __init__(self, guided: str | Path | None = None, local_model: str = "text", device: str = "cpu"):
        self.glb = glb_available()  # once: what the page says and what `generate` writes agree
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

    def info(self, key: str) -> ModelInfo:
        pipe = self.get(key)
        if isinstance(pipe, GuidedMotionPipeline):
            decoder = pipe.latent.decoder.hparams
            guidance = float((pipe.latent.hparams.sampling or {}).get("guidance", 7.5))  # the latent model's default
            return ModelInfo("guided", int(decoder.max_frames) / pipe.fps, guidance)
        parts = sorted(pipe.model.representation.skeleton.parts)
        return ModelInfo(pipe.condition_kind, pipe.max_seconds, float(pipe.model.default_guidance), pipe.actions, parts)


def parse_weights(text: str | None) -> list[float] | None:
    """GuidedMotion's local-action weights from the page: "2, 0.5" (one per local action); empty: None (1 each)."""
    if text is None or not str(text).strip():
        return None
    try:
        return [float(w) for w in str(text).replace(";", ",").split(",") if w.strip()]
    except ValueError:
        raise UsageError(
            f"local action weights must be numbers separated by commas, e.g. 2, 0.5; got {text!r}"
        ) from None


def write_npz(path: Path, joints: np.ndarray, features: np.ndarray, fps: float) -> Path:
    """One motion in one file: joints (frames, J, 3) in metres, y up; the model's features; fps."""
    np.savez(path, joints=np.asarray(joints, np.float32), features=np.asarray(features, np.float32), fps=float(fps))
    return path


def generate(
    models: DemoModels,
    key: str,
    prompt: str | None,
    out_dir: str | Path,
    *,
    seconds: float,
    guidance: float | None = None,
    seed: int = 0,
    num_samples: int = 1,
    steps: int | None = None,
    weights: str | None = None,
) -> tuple[MotionOutput, list[Sample]]:
    """Generate ``num_samples`` motions of ``prompt`` (a text, or an action model's action name) with model ``key``
    and write each one's viewer, MP4, BVH and NPZ under ``out_dir``, and a GLB when ``models.glb`` (a Blender
    failure leaves it out and is in the sample's ``glb_error``)."""
    num_samples = _whole(num_samples, "number of samples", 1, MAX_SAMPLES)
    seed = _whole(seed, "seed", 0, 2**63 - 1)
    steps = None if steps in (None, "") else _whole(steps, "steps", 1, 10_000)
    pipe = models.get(key)
    if isinstance(pipe, GuidedMotionPipeline):
        level_steps = None if steps is None else (steps, steps, steps)
        out = pipe(prompt, seconds=float(seconds), num_samples=num_samples, guidance=guidance, seed=seed,
                   level_steps=level_steps, local_weights=parse_weights(weights))  # fmt: skip
    else:
        if pipe.condition_kind == "action" and (prompt is None or not str(prompt).strip()):
            raise UsageError(f"choose an action: one of {', '.join(pipe.actions)}")
        out = pipe(
            prompt,
            seconds=float(seconds),
            num_samples=num_samples,
            guidance=guidance,
            sampler="ddim",
            steps=steps,
            seed=seed,
        )  # the page's steps slider is DDIM's (GuidedMotion samples with DDIM too)
    return out, _write_samples(models, out, Path(out_dir))


def edit_parts(
    models: DemoModels,
    key: str,
    motion: MotionOutput,
    prompt: str | None,
    parts,
    out_dir: str | Path,
    *,
    seed: int = 0,
    steps: int | None = None,
    guidance: float | None = None,
) -> tuple[MotionOutput, list[Sample]]:
    """Regenerate ``parts`` of the first motion of ``motion`` from ``prompt`` and keep the rest of the body: ``parts``
    names the parts that are REGENERATED, as ``edit.py parts=`` and ``MotionPipeline.edit_parts(parts=)`` do."""
    pipe = models.get(key)
    if isinstance(pipe, GuidedMotionPipeline):
        raise UsageError("body-part editing needs an MDM model (text or action): choose one in the model list")
    if motion is None:
        raise UsageError("generate a motion first: the edit regenerates parts of sample 1")
    if not parts:
        raise UsageError(
            f"choose the body parts to regenerate: {', '.join(sorted(pipe.model.representation.skeleton.parts))}"
        )
    seed = _whole(seed, "seed", 0, 2**63 - 1)
    steps = None if steps in (None, "") else _whole(steps, "steps", 1, 10_000)
    out = pipe.edit_parts(motion, prompt, parts=list(parts) if not isinstance(parts, str) else parts, seed=seed,
                          sampler="ddim", steps=steps, guidance=guidance)  # fmt: skip
    return out, _write_samples(models, replace(out, edit=None), Path(out_dir))


def _write_samples(models: DemoModels, out: MotionOutput, out_dir: Path) -> list[Sample]:
    """Each motion's viewer, MP4, BVH and NPZ (and GLB with Blender) under ``out_dir``, as the page offers them."""
    rows = out.save(out_dir, formats=["bvh", "mp4", "html"])
    samples = []
    for i, row in enumerate(rows):
        exports = row["exports"]
        npz = write_npz(Path(exports["bvh"]).with_suffix(".npz"), out.joints[i], out.features[i], out.fps)
        title = f"sample {i + 1}: {out.prompts[i] or 'unconditioned'}, {out.seconds(i):.1f} s at {out.fps:g} fps"
        glb, error = _glb(Path(exports["bvh"]), out.fps) if models.glb else (None, None)
        samples.append(Sample(i, title, Path(exports["html"]), Path(exports["mp4"]), Path(exports["bvh"]), npz, glb,
                              error))  # fmt: skip
    return samples


def _glb(bvh: Path, fps: float) -> tuple[Path | None, str | None]:
    """The GLB Blender writes from the sample's BVH (as export=glb does), or None and why Blender failed: the other
    files are still offered."""
    try:
        return convert_bvh(bvh, bvh.with_suffix(".glb"), fps), None
    except (RuntimeError, OSError, subprocess.TimeoutExpired, UsageError) as err:
        return None, str(err)


def _whole(value, name: str, low: int, high: int) -> int:
    """A whole number from the page (Gradio numbers arrive as floats)."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise UsageError(f"{name} must be a whole number, got {value!r}") from None
    if not number.is_integer() or not low <= number <= high:
        raise UsageError(f"{name} must be a whole number in {low}..{high}, got {value!r}")
    return int(number)
