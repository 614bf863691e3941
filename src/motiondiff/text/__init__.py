"""Text side: frozen sentence encoders (MiniLM bundled, CLIP from local weights) and the caption feature cache."""

from motiondiff.text.cache import TextEmbeddingCache
from motiondiff.text.encoders import (
    CLIPTextEncoder,
    CLIPWeightsNotFoundError,
    MiniLMEncoder,
    TextEncoder,
    build_text_encoder,
)

__all__ = [
    "CLIPTextEncoder",
    "CLIPWeightsNotFoundError",
    "MiniLMEncoder",
    "TextEmbeddingCache",
    "TextEncoder",
    "build_text_encoder",
]
