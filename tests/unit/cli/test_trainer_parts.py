"""cli.common.trainer_parts: loggers and callbacks from the config; logger=none trains (no learning-rate monitor)."""

from __future__ import annotations

import pytest
from hydra import compose, initialize_config_dir
from hydra.core.global_hydra import GlobalHydra
from lightning.pytorch.callbacks import LearningRateMonitor, ModelCheckpoint
from lightning.pytorch.loggers import CSVLogger
from omegaconf import open_dict

from motiondiff.cli.common import REPO_DIR, register_resolvers, trainer_parts

register_resolvers()


@pytest.mark.parametrize("entry", ["train", "train_vae", "train_latent"])
def test_logger_none_drops_only_the_rate_monitor(entry, tmp_path):
    GlobalHydra.instance().clear()
    with initialize_config_dir(config_dir=str(REPO_DIR / "conf"), version_base="1.3"):
        overrides = [f"hydra.run.dir={tmp_path}"]
        none = compose(entry, overrides=[*overrides, "logger=none"], return_hydra_config=True)
        csv = compose(entry, overrides=[*overrides, "logger=csv"], return_hydra_config=True)
    from hydra.core.hydra_config import HydraConfig

    for cfg in (none, csv):  # what a real run sets before the job starts
        with open_dict(cfg):
            cfg.hydra.runtime.output_dir = str(tmp_path)
    HydraConfig.instance().set_config(none)
    loggers, callbacks = trainer_parts(none)
    assert loggers == [] and not any(isinstance(c, LearningRateMonitor) for c in callbacks)
    assert any(isinstance(c, ModelCheckpoint) for c in callbacks)
    HydraConfig.instance().set_config(csv)
    loggers, with_logger = trainer_parts(csv)
    assert isinstance(loggers[0], CSVLogger) and any(isinstance(c, LearningRateMonitor) for c in with_logger)
    assert len(with_logger) == len(callbacks) + 1


def test_a_bad_callback_setting_is_one_user_error(tmp_path):
    """Hydra wraps what a constructor raises in InstantiationException (a traceback); a UsageError comes out as
    itself, so the command prints one line."""
    from omegaconf import OmegaConf

    from motiondiff.runtime.errors import UsageError

    cfg = OmegaConf.create({"callbacks": {"evaluation": {
        "_target_": "motiondiff.eval.callbacks.GenerationEvaluation", "evaluator_dir": str(tmp_path),
        "videos": {"count": 0}}}})  # fmt: skip
    with pytest.raises(UsageError, match=r"^callbacks\.evaluation\.videos\.count=0: must be an integer"):
        trainer_parts(cfg)
