"""Denoising networks: MDMDenoiser = input projection + time/condition token + backbone + output projection."""

from motiondiff.models.backbones import BACKBONES, build_backbone
from motiondiff.models.conditioning import ActionCondition, NoCondition, TextCondition, build_condition
from motiondiff.models.denoiser import PRESETS, MDMDenoiser, build_denoiser, count_parameters
from motiondiff.models.embeddings import SinusoidalPositionalEncoding, TimestepEmbedder

__all__ = [
    "BACKBONES",
    "PRESETS",
    "ActionCondition",
    "MDMDenoiser",
    "NoCondition",
    "SinusoidalPositionalEncoding",
    "TextCondition",
    "TimestepEmbedder",
    "build_backbone",
    "build_condition",
    "build_denoiser",
    "count_parameters",
]
