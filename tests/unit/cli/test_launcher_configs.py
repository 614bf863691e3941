"""Scaling configs compose as documented: trainer=ddp (Lightning DDP, 2 CPU processes by default) and
hydra/launcher=slurm (Hydra's submitit launcher, one task per device so Lightning's DDP spans the allocation)."""

from __future__ import annotations

from pathlib import Path

from hydra import compose, initialize_config_dir
from hydra.utils import get_class

CONF = Path(__file__).resolve().parents[3] / "conf"


def _compose(*overrides: str):
    with initialize_config_dir(str(CONF), version_base="1.3"):
        return compose("train", overrides=list(overrides), return_hydra_config=True)


def test_ddp_trainer_runs_two_cpu_processes_unless_told_otherwise():
    cfg = _compose("trainer=ddp")
    assert (cfg.trainer.strategy, cfg.trainer.devices, cfg.trainer.num_nodes, cfg.trainer.accelerator) == (
        "ddp",
        2,
        1,
        "cpu",
    )
    assert cfg.trainer.gradient_clip_val == 1.0  # the rest of the CPU trainer is kept


def test_slurm_launcher_sizes_the_allocation_from_the_trainer():
    cfg = _compose(
        "hydra/launcher=slurm", "trainer=ddp", "trainer.accelerator=gpu", "trainer.devices=8", "trainer.num_nodes=2"
    )
    launcher = cfg.hydra.launcher
    assert get_class(launcher._target_).__name__ == "SlurmLauncher"
    assert (launcher.nodes, launcher.tasks_per_node, launcher.gpus_per_node) == (2, 8, 8)
    single = _compose("hydra/launcher=slurm").hydra.launcher  # the plain CPU trainer: one task, one node
    assert (single.nodes, single.tasks_per_node) == (1, 1)
