"""The commands: `motiondiff-train`, `-sample`, `-edit`, `-evaluate`, `-train-vae`, `-train-latent`, `-demo` (console
scripts of an installed package) and the root scripts of a checkout (`python train.py ...`), one Hydra run each with
the project's configs (the web demo: argparse options, see motiondiff.cli.demo). Every user error is one `error: ...`
line and exit code 2."""

from __future__ import annotations

from motiondiff.cli import validate
from motiondiff.cli.prompt_inputs import check_prompt_inputs
from motiondiff.model_files.file_checks import check_model_file
from motiondiff.model_files.resolve import find_model
from motiondiff.runtime.hardware import resolve_device
from motiondiff.runtime.scripting import run_hydra as _run

# The rule tables, the prompts and the model file are checked before a command imports Lightning and the text
# encoder (about 7 s of CPU on a 2-core machine), so a mistyped number, an empty prompt or a corrupt model is refused
# at once; each command checks them again itself (for callers that skip these entry points).


def _before_model(cfg, condition: str = "text") -> None:
    """The checks of a command that need no model: its device, and its model file (``checkpoint=``)."""

    if str(cfg.get("device", "cpu")).strip().lower() not in ("cpu", "auto"):
        resolve_device(cfg.device)
    check_model_file(find_model(cfg.checkpoint, cfg.paths.output_dir, condition))


def _checked(name: str, rules, command, model: bool = True) -> None:
    """Hydra command `name`: its config passes `rules` (and, with `model`, `_before_model`) before `command()` gives
    the run function, so a refused config never pays for the command's imports."""

    def run(cfg):
        validate.check(cfg, rules)
        if model:
            _before_model(cfg)
        return command()(cfg)

    _run(name, run)


def train() -> None:
    def command():
        from motiondiff.cli.train import run  # lazy: lightning (+4.4 s to import)

        return run

    _checked("train", validate.RULES_TRAIN, command, model=False)


def sample() -> None:
    def run(cfg):
        validate.check(cfg, validate.RULES_SAMPLE)
        if cfg.get("method", "mdm") == "guidedmotion":
            from motiondiff.cli.sample_guided import run as guided  # lazy: lightning, spacy (+5.1 s to import)

            return guided(cfg)

        check_prompt_inputs(cfg)
        _before_model(cfg, "action" if cfg.get("action") is not None else "text")
        from motiondiff.cli.sample import run as mdm  # lazy: lightning, the pipelines (+4.4 s to import)

        return mdm(cfg)

    _run("sample", run)


def edit() -> None:
    def command():
        from motiondiff.cli.edit import run  # lazy: lightning, the pipelines (+4.4 s to import)

        return run

    _checked("edit", validate.RULES_EDIT, command)


def evaluate() -> None:
    def command():
        from motiondiff.cli.evaluate import run  # lazy: torchmetrics (+2.6 s to import)

        return run

    _checked("evaluate", validate.RULES_EVALUATE, command)


def train_vae() -> None:
    from motiondiff.cli.train_vae import run  # lazy: lightning (+4.4 s to import)

    _run("train_vae", run)


def train_latent() -> None:
    from motiondiff.cli.train_latent import run  # lazy: lightning, spacy (+5.1 s to import)

    _run("train_latent", run)


def train_evaluator() -> None:
    from motiondiff.cli.train_evaluator import run  # lazy: lightning, torchmetrics (+7.0 s to import)

    _run("train_evaluator", run)


def demo() -> None:
    from motiondiff.cli.demo import main  # lazy: gradio, the pipelines (+8 s to import)

    main()
