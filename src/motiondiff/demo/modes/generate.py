"""Generate mode: ``num_samples`` motions of one prompt (a text, an action model's action, a GuidedMotion caption)."""

from __future__ import annotations

from motiondiff.demo.inputs import parse_weights, steps_of, whole
from motiondiff.demo.models import MAX_SAMPLES, DemoModels
from motiondiff.pipelines import GuidedMotionPipeline, MotionOutput
from motiondiff.runtime.errors import UsageError


def generate(
    models: DemoModels,
    key: str,
    prompt: str | None,
    *,
    seconds: float,
    guidance: float | None = None,
    seed: int = 0,
    num_samples: int = 1,
    steps: int | None = None,
    weights: str | None = None,
) -> MotionOutput:
    """Sample ``prompt`` with model ``key``: DDIM with ``steps`` (GuidedMotion: per level), ``guidance`` (None: the
    model's default); ``weights``: GuidedMotion's local-action weights as typed ("2, 0.5")."""
    num_samples = whole(num_samples, "number of samples", 1, MAX_SAMPLES)
    seed = whole(seed, "seed", 0, 2**63 - 1)
    steps = steps_of(steps)
    pipe = models.get(key)
    if isinstance(pipe, GuidedMotionPipeline):
        level_steps = None if steps is None else (steps, steps, steps)
        return pipe(prompt, seconds=float(seconds), num_samples=num_samples, guidance=guidance, seed=seed,
                    level_steps=level_steps, local_weights=parse_weights(weights))  # fmt: skip
    if pipe.condition_kind == "action" and (prompt is None or not str(prompt).strip()):
        raise UsageError(f"choose an action: one of {', '.join(pipe.actions)}")
    return pipe(prompt, seconds=float(seconds), num_samples=num_samples, guidance=guidance, sampler="ddim",
                steps=steps, seed=seed)  # fmt: skip
