"""Train GuidedMotion's hierarchical latent diffusion: python train_latent.py vae.motion=... vae.action=... ..."""

from motiondiff.cli.entry import train_latent

if __name__ == "__main__":
    train_latent()
