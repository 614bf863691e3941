"""The commands: `motiondiff-train`, `-sample`, `-edit`, `-evaluate`, `-train-vae`, `-train-latent`, `-demo` (console
scripts of an installed package) and the root scripts of a checkout (`python train.py ...`), one Hydra run each with
the project's configs (the web demo: argparse options, see motiondiff.cli.demo). Every user error is one `error: ...`
line and exit code 2."""

from __future__ import annotations

from motiondiff.cli import validate
from motiondiff.scripting import run_hydra as _run

# The rule tables are checked before a command imports torch and Lightning (seconds), so a mistyped number is refused
# at once; each command checks them again itself (for callers that skip these entry points).


def train() -> None:
    def run(cfg):
        validate.check(cfg, validate.RULES_TRAIN)
        from motiondiff.cli.train import run as train_run

        return train_run(cfg)

    _run("train", run)


def sample() -> None:
    def run(cfg):
        validate.check(cfg, validate.RULES_SAMPLE)
        if cfg.get("method", "mdm") == "guidedmotion":
            from motiondiff.cli.sample_guided import run as guided

            return guided(cfg)
        from motiondiff.cli.sample import run as mdm

        return mdm(cfg)

    _run("sample", run)


def edit() -> None:
    def run(cfg):
        validate.check(cfg, validate.RULES_EDIT)
        from motiondiff.cli.edit import run as edit_run

        return edit_run(cfg)

    _run("edit", run)


def evaluate() -> None:
    def run(cfg):
        validate.check(cfg, validate.RULES_EVALUATE)
        from motiondiff.cli.evaluate import run as evaluate_run

        return evaluate_run(cfg)

    _run("evaluate", run)


def train_vae() -> None:
    from motiondiff.cli.train_vae import run

    _run("train_vae", run)


def train_latent() -> None:
    from motiondiff.cli.train_latent import run

    _run("train_latent", run)


def train_evaluator() -> None:
    from motiondiff.cli.train_evaluator import run

    _run("train_evaluator", run)


def demo() -> None:
    from motiondiff.cli.demo import main

    main()
