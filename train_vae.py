"""Train a GuidedMotion motion VAE: python train_vae.py [level=motion|action|specific] [vae=cpu|paper] ..."""

from motiondiff.cli.entry import train_vae

if __name__ == "__main__":
    train_vae()
