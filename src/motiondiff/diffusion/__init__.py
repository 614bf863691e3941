"""Diffusion math, independent of motion: schedules, the Gaussian process, samplers and guidance."""

from motiondiff.diffusion.dpm_solver import dpmpp_sample
from motiondiff.diffusion.guidance import classifier_free_guidance, guided_model_fn, overwrite_known
from motiondiff.diffusion.process import PREDICTIONS, WEIGHTINGS, GaussianDiffusion, masked_mean_per_sample
from motiondiff.diffusion.samplers import ddim_coefficients, ddim_sample, ddpm_sample, select_timesteps
from motiondiff.diffusion.schedules import SCHEDULES, make_betas

__all__ = [
    "PREDICTIONS",
    "SCHEDULES",
    "WEIGHTINGS",
    "GaussianDiffusion",
    "classifier_free_guidance",
    "ddim_coefficients",
    "ddim_sample",
    "ddpm_sample",
    "dpmpp_sample",
    "guided_model_fn",
    "make_betas",
    "masked_mean_per_sample",
    "overwrite_known",
    "select_timesteps",
]
