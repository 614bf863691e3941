"""Train a motion diffusion model: python train.py [backbone=... dataset=... condition=... model=paper ...]"""

from motiondiff.cli.entry import train

if __name__ == "__main__":
    train()
