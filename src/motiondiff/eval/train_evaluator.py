"""`python -m motiondiff.eval.train_evaluator dataset=<name> [evaluator_model=small|paper] [which=[...]]`

Trains a dataset's text-motion evaluator and action classifier and releases them (see motiondiff.cli.train_evaluator).
"""

import hydra

from motiondiff.cli.common import REPO_DIR, quiet_tool_caches, register_resolvers, user_errors

register_resolvers()
quiet_tool_caches()


@hydra.main(version_base="1.3", config_path=str(REPO_DIR / "conf"), config_name="train_evaluator")
@user_errors
def main(cfg):
    from motiondiff.cli.train_evaluator import run

    run(cfg)


if __name__ == "__main__":
    main()
