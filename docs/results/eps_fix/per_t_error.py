"""Issue 43 point 2's account: how well an ε model and an x0 model of the full Bandai set predict the clean motion at
each noise level, and how much each training loss weighs that error there.

    .venv/bin/python docs/results/eps_fix/per_t_error.py <model> <model> ... > out.md

For each model (a .ckpt or release) and t in T_VALUES: real val clips (the first CLIPS with at least FRAMES frames,
normalised features) noised to t with NOISES draws each, the unconditioned branch; the RMS of x̂0 − x0 and of
ε̂ − ε, whatever the network predicts. Beside them, the weight the ε loss gives to x̂0's error at t (SNR(t): the ε
loss is SNR(t) times the x0 loss) against the x0 loss's 1.
"""

import sys

import torch

from motiondiff.data.datamodules import PreparedDataModule
from motiondiff.eval.prediction_error import prediction_errors
from motiondiff.model_files.loading import load_model

CLIPS, FRAMES, NOISES = 32, 80, 2
T_VALUES = (999, 980, 900, 700, 500, 300, 100, 20)


def label(path: str) -> str:
    """A run's checkpoint by its run folder and file (<run>/checkpoints/<file>.ckpt), a release by its name."""
    parts = path.rstrip("/").split("/")
    name = parts[-1].removesuffix(".ckpt").removesuffix(".safetensors")
    return f"{parts[-3]} {name}" if len(parts) >= 3 and parts[-2] == "checkpoints" else name


def val_clips(representation: str | None) -> torch.Tensor:
    """The first CLIPS val clips of at least FRAMES frames, normalised, in a model's feature layout (hml263 when the
    model names none): the same clips for every layout, so models of different representations are compared on
    one motion."""
    extra = {"representation": representation} if representation else {}
    dm = PreparedDataModule("data/bandai", batch_size=8, max_frames=FRAMES, **extra)
    dm.setup("fit")
    val = dm.dataset("val")
    items = (val[i] for i in range(len(val)))
    clips = [it["motion"][:FRAMES] for it in items if len(it["motion"]) >= FRAMES][:CLIPS]
    return torch.stack([torch.as_tensor(c) for c in clips]).float()


def main() -> None:
    models = [(path, load_model(path)) for path in sys.argv[1:]]
    layouts = [(m.hparams.get("representation") or {}).get("name") for _, m in models]
    clips = {layout: val_clips(layout) for layout in dict.fromkeys(layouts)}  # one load per feature layout
    snr = models[0][1].diffusion.snr
    print(
        f"`{' '.join(sys.argv)}`: {len(next(iter(clips.values())))} real val clips of the full Bandai set, {FRAMES} frames, normalised "
        f"features (each model's own: {', '.join(x or 'hml263' for x in layouts)}), {NOISES} noise draws each, "
        f"the unconditioned branch (seed 0).\n"
    )
    head = " | ".join(f"{label(p)}: RMS x̂0 − x0 | RMS ε̂ − ε" for p, _ in models)
    print(f"| t | SNR(t): the ε loss's weight on x̂0's error (x0 loss: 1) | {head} |")
    print("|---:|---:|" + "---:|---:|" * len(models))
    table = [
        prediction_errors(m, clips[layout], T_VALUES, NOISES) for (_, m), layout in zip(models, layouts, strict=True)
    ]
    for i, t in enumerate(T_VALUES):
        cells = " | ".join(f"{rows[i][1]:.3g} | {rows[i][2]:.3g}" for rows in table)
        print(f"| {t} | {float(snr[t]):.3g} | {cells} |")


if __name__ == "__main__":
    main()
