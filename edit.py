"""Edit a motion: python edit.py input=<file.bvh | joints.npy | clip id> kind=inbetween|parts [text="..." ...]"""

import hydra

from motiondiff.cli.common import quiet_tool_caches, register_resolvers, user_errors

register_resolvers()
quiet_tool_caches()


@hydra.main(version_base="1.3", config_path="conf", config_name="edit")
@user_errors
def main(cfg):
    from motiondiff.cli.edit import run

    run(cfg)


if __name__ == "__main__":
    main()
