"""Release the mirrored GuidedMotion run's v latent (run.sh beside this file) as checkpoints/models/bandai_guided_cpu:
the latent model's last checkpoint with its three VAEs, and what it was trained on, how long and where.

    .venv/bin/python docs/results/guidedmotion/mirror_release/release.py [outputs/guided_mirror]
"""

import json
import sys
from pathlib import Path

from motiondiff.model_files.release import cpu_description, release_checkpoint
from motiondiff.runtime.hardware import fast_cpu_precision

gc = Path(sys.argv[1] if len(sys.argv) > 1 else "outputs/guided_mirror")
stages = {s: json.loads((gc / s / "run.json").read_text()) for s in ("vae_motion", "vae_action", "vae_specific", "latent_v")}
minutes = {s: round(r["train_seconds"] / 60, 1) for s, r in stages.items()}
release_checkpoint(
    gc / "latent_v" / "checkpoints" / "last.ckpt",
    "checkpoints/models/bandai_guided_cpu",
    half_matrices=True,  # 30.6 MB in float32; matrices in float16 keep the samples (checked in the card)
    dataset="bandai_mini_compositional: 64 composed train sequences (2-3 real Bandai Namco clips joined) and the 252 "
    "embedded single train clips, every one also left-right mirrored; captions GENERATED, none human-written",
    recipe="make guided-compare's CPU recipe: three motion VAEs (Q = 2/4/8, batch 16, AdamW 5e-4, 960 steps each; the "
    "last checkpoint), then the latent diffusion (v prediction with SNR weighting, scaled_linear, batch 32, AdamW 2e-4 "
    "cosine with 200 warm-up steps, 5,000 steps), the CPU recipe of docs/guidedmotion.md; "
    "docs/results/guidedmotion/mirror_release/run.sh",
    train_minutes=minutes,
    vae_steps={s: stages[s]["train_steps"] for s in ("vae_motion", "vae_action", "vae_specific")},
    precision=fast_cpu_precision(),  # what the CPU presets trained the stages in (run this on the machine that trained)
    machine=cpu_description(),
    license="CC BY-NC 4.0: derived from the Bandai Namco Research Motion Dataset (Bandai Namco Research Inc.)",
)
print("released checkpoints/models/bandai_guided_cpu.{safetensors,json}")
