"""Issue 43 point 2, the diagnosis: why an ε-prediction model's samples have no smoothness here.

For one trained model, DDIM-50 on val captions, it records the RMS of x̂0 (normalised features) at each step and the
vvMDM smoothness of the result, with variants of the first steps: as trained (DDIM on t = 999, 979, ..., 0), x̂0 at
t = 999 replaced by 0 (the data mean), the static safe-x̂0 clip, and the official MDM code's DDIM-50 steps
(guided-diffusion's "ddim50" respacing: t = 980, 960, ..., 0, never 999; patched in here for the probe only). An x0
model is measured the same way for reference.

    .venv/bin/python docs/results/eps_probe/probe.py <eps .ckpt> [<x0 .ckpt or release>] [out.md]
"""

import sys
from pathlib import Path

import numpy as np
import torch

import motiondiff.diffusion.samplers as samplers
from motiondiff.data.datamodules import PreparedDataModule, embedded_data_root
from motiondiff.diffusion.schedules import make_betas
from motiondiff.eval.prediction_error import prediction_errors as errors
from motiondiff.lit.generation import generate_features
from motiondiff.metrics.spread import smoothness
from motiondiff.model_files.loading import load_model

CLIPS, FRAMES = 32, 60


def run(model, captions, variant: str) -> tuple[list[float], float, float]:
    rms: list[float] = []

    def hook(x0, t):
        if variant == "zero_at_999" and int(t if isinstance(t, int) else t.flatten()[0]) == 999:
            x0 = torch.zeros_like(x0)
        rms.append(float(x0.pow(2).mean().sqrt()))
        return x0

    if variant == "static_clip":
        model.set_clip_rule("static")
    uniform = samplers.select_timesteps
    if variant == "official_ddim50":  # guided-diffusion's space_timesteps(1000, "ddim50"): range(0, 1000, 20)
        samplers.select_timesteps = lambda num_steps, steps=None, *a, **k: list(range(0, num_steps, num_steps // steps))
    feats = generate_features(model, captions, torch.full((len(captions),), FRAMES), 64,
                              torch.Generator().manual_seed(0), None, "32-true", sampler="ddim", steps=50,
                              guidance=model.default_guidance, x0_hook=hook)  # fmt: skip
    samplers.select_timesteps = uniform
    model.set_clip_rule(None if variant == "static_clip" else model.clip_rule)
    smooth = float(np.mean([smoothness(f) for f in feats]))
    normed = np.concatenate([(f - model.mean.numpy()) / model.std.numpy() for f in feats])
    return rms, smooth, float(np.sqrt((normed**2).mean()))


def prediction_errors(model, val) -> list[str]:
    """RMS of ε̂ − ε and of x̂0 − x0 on 16 real val clips noised to t (the unconditioned branch, seed 0)."""
    clips = [it["motion"][:FRAMES] for it in (val[i] for i in range(len(val))) if len(it["motion"]) >= FRAMES][:16]
    x0 = torch.stack([torch.as_tensor(np.asarray(c)) for c in clips]).float()
    rows = []
    for t, rms_x0, rms_eps in errors(model, x0, (999, 980, 900, 500, 100, 10)):
        rows.append(f"| {model.hparams.diffusion['prediction']} | {t} | {rms_eps:.3f} | {rms_x0:.3g} |")
    return rows


def main():
    eps_ckpt = sys.argv[1]
    x0_ckpt = sys.argv[2] if len(sys.argv) > 2 else None
    out = Path(sys.argv[3] if len(sys.argv) > 3 else "docs/results/eps_probe/README.md")
    dm = PreparedDataModule(embedded_data_root(), batch_size=8, max_frames=FRAMES)
    dm.setup("fit")
    val = dm.dataset("val")
    captions = [val.records[i].texts[0] for i in range(min(CLIPS, len(val.records)))]
    real = float(np.mean([smoothness(r.motion[:FRAMES]) for r in val.records[:CLIPS]]))
    abar = torch.cumprod(1 - make_betas("cosine", 1000), 0)
    rows, errors = [], []
    for name, path, variants in [("ε", eps_ckpt, ("as_trained", "zero_at_999", "static_clip", "official_ddim50")),
                                 ("x0", x0_ckpt, ("as_trained", "official_ddim50"))]:  # fmt: skip
        if path is None:
            continue
        model = load_model(path)
        errors += prediction_errors(model, val)
        for v in variants:
            rms, smooth, final = run(model, captions, v)
            rows.append(f"| {name} | {v} | {rms[0]:.3g} | {rms[1]:.3g} | {rms[2]:.3g} | {rms[-1]:.3g} | {final:.3g} | "
                        f"{smooth:.4f} |")  # fmt: skip
    text = "\n".join([
        "# Why ε-prediction makes no motion here (issue 43, point 2): the probe", "",
        f"Cosine schedule, β clipped at 0.999: ᾱ_998 = {abar[998]:.3g}, ᾱ_999 = {abar[999]:.3g}, so at t = 999 "
        f"x̂0 = (x_t − √(1−ᾱ) ε̂)/√ᾱ multiplies any error of ε̂ by 1/√ᾱ_999 = {1 / abar[999].sqrt():.0f}; DDIM's "
        f"first step to t = 979 carries it into x_979 with √(ᾱ_979/ᾱ_999) = {(abar[979] / abar[999]).sqrt():.0f}. "
        "An x0 model predicts x̂0 directly and has no such factor.", "",
        f"`{' '.join(sys.argv)}`; {len(captions)} val captions of the embedded data, {FRAMES} frames, DDIM-50, the "
        f"model's guidance, seed 0. RMS of x̂0 in normalised features (the data: 1); smoothness (vvMDM eq. 16) of "
        f"the de-normalised features; real val clips: **{real:.4f}**.", "",
        "| prediction | variant | x̂0 RMS, step 1 | step 2 | step 3 | last step | result RMS | smoothness |",
        "|---|---|---:|---:|---:|---:|---:|---:|", *rows, "",
        "Errors of the network's prediction on real val clips noised to t (16 clips, 60 frames, unconditioned):", "",
        "| prediction | t | RMS ε̂ − ε | RMS x̂0 − x0 |", "|---|---:|---:|---:|", *errors, ""])  # fmt: skip
    out.write_text(text)
    print(text)


if __name__ == "__main__":
    main()
