"""Generate motion: python sample.py text="a person walks forward" [num_samples=3 guidance=2.5 length=4 ...]"""

import hydra

from motiondiff.cli.common import quiet_tool_caches, register_resolvers, user_errors

register_resolvers()
quiet_tool_caches()


@hydra.main(version_base="1.3", config_path="conf", config_name="sample")
@user_errors
def main(cfg):
    if cfg.get("method", "mdm") == "guidedmotion":
        from motiondiff.cli.sample_guided import run
    else:
        from motiondiff.cli.sample import run
    run(cfg)


if __name__ == "__main__":
    main()
