"""The user-facing Python API: load a released or trained model and generate, edit or chain motion in a few lines.

from motiondiff.pipelines import MotionPipeline
pipe = MotionPipeline.from_pretrained("text")
out = pipe("a person walks forward", seconds=4)
out.save("out", formats=["bvh", "mp4"])
"""

from motiondiff.model_files.resolve import find_model
from motiondiff.pipelines.motion import MotionPipeline
from motiondiff.pipelines.output import MotionOutput


def __getattr__(name: str):
    """GuidedMotionPipeline on first use: its latent models are LightningModules, and importing Lightning costs
    seconds that text-to-motion generation does not need."""
    if name == "GuidedMotionPipeline":
        from motiondiff.pipelines.guided import GuidedMotionPipeline  # lazy: lightning, spacy (+5.1 s to import)

        return GuidedMotionPipeline
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["GuidedMotionPipeline", "MotionOutput", "MotionPipeline", "find_model"]
