"""Generate mode: ``num_samples`` motions of one prompt (a text, an action model's action, a GuidedMotion caption)."""

from __future__ import annotations

from motiondiff.demo.inputs import DEFAULT_SAMPLING, Sampling, parse_weights
from motiondiff.demo.models import DemoModels
from motiondiff.pipelines import GuidedMotionPipeline, MotionOutput
from motiondiff.runtime.errors import UsageError


def generate(
    models: DemoModels,
    key: str,
    prompt: str | None,
    *,
    seconds: float,
    sampling: Sampling = DEFAULT_SAMPLING,
    weights: str | None = None,
) -> MotionOutput:
    """Sample ``prompt`` with model ``key`` by ``sampling`` (GuidedMotion: its ``steps`` at each level);
    ``weights``: GuidedMotion's local-action weights as typed ("2, 0.5")."""
    pipe = models.get(key)
    if isinstance(pipe, GuidedMotionPipeline):
        level_steps = None if sampling.steps is None else (sampling.steps,) * 3
        return pipe(prompt, seconds=float(seconds), num_samples=sampling.num_samples, guidance=sampling.guidance,
                    seed=sampling.seed, level_steps=level_steps, local_weights=parse_weights(weights))  # fmt: skip
    if pipe.condition_kind == "action" and (prompt is None or not str(prompt).strip()):
        raise UsageError(f"choose an action: one of {', '.join(pipe.actions)}")
    return pipe(prompt, seconds=float(seconds), **sampling.ddim())
