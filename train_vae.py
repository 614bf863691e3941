"""Train a GuidedMotion motion VAE: python train_vae.py [level=motion|action|specific] [vae=cpu|paper] ..."""

import hydra

from motiondiff.cli.common import quiet_tool_caches, register_resolvers, user_errors

register_resolvers()
quiet_tool_caches()


@hydra.main(version_base="1.3", config_path="conf", config_name="train_vae")
@user_errors
def main(cfg):
    from motiondiff.cli.train_vae import run

    run(cfg)


if __name__ == "__main__":
    main()
