"""Evaluate a trained model: python evaluate.py [checkpoint=...] [replications=20]; sweep: -m guidance=0,1,2.5,5"""

import hydra

from motiondiff.cli.common import quiet_tool_caches, register_resolvers, user_errors

register_resolvers()
quiet_tool_caches()


@hydra.main(version_base="1.3", config_path="conf", config_name="evaluate")
@user_errors
def main(cfg):
    from motiondiff.cli.evaluate import run

    run(cfg)


if __name__ == "__main__":
    main()
