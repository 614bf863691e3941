"""The commands: `motiondiff-train`, `-sample`, `-edit`, `-evaluate`, `-train-vae`, `-train-latent`, `-demo` (console
scripts of an installed package) and the root scripts of a checkout (`python train.py ...`), one Hydra run each with
the project's configs (the web demo: argparse options, see motiondiff.cli.demo). Every user error is one `error: ...`
line and exit code 2."""

from __future__ import annotations

from motiondiff.scripting import run_hydra as _run


def train() -> None:
    from motiondiff.cli.train import run

    _run("train", run)


def sample() -> None:
    def run(cfg):
        if cfg.get("method", "mdm") == "guidedmotion":
            from motiondiff.cli.sample_guided import run as guided

            return guided(cfg)
        from motiondiff.cli.sample import run as mdm

        return mdm(cfg)

    _run("sample", run)


def edit() -> None:
    from motiondiff.cli.edit import run

    _run("edit", run)


def evaluate() -> None:
    from motiondiff.cli.evaluate import run

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
