"""Train GuidedMotion's hierarchical latent diffusion: python train_latent.py vae.motion=... vae.action=... ..."""

import hydra

from motiondiff.cli.common import quiet_tool_caches, register_resolvers, user_errors

register_resolvers()
quiet_tool_caches()


@hydra.main(version_base="1.3", config_path="conf", config_name="train_latent")
@user_errors
def main(cfg):
    from motiondiff.cli.train_latent import run

    run(cfg)


if __name__ == "__main__":
    main()
