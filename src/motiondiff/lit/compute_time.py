"""The compute a training run has spent, logged beside its losses and summed across sittings.

Runs on these CPUs are stopped and resumed (a session's end, `kill -9` after a checkpoint), so neither the wall time
of one process nor a sitting's start/end lines give the compute of a run. ``ComputeTime`` logs, every
``log_every_n_steps``, ``compute/cpu_minutes`` (the process's CPU time over the threads torch uses, i.e. minutes of
the whole CPU at full use) and ``compute/wall_minutes``, and keeps both totals in the checkpoint, so a resumed run
goes on counting from the step it resumed at (the killed part after that checkpoint is not counted twice).
"""

from __future__ import annotations

import time

import torch
from lightning.pytorch.callbacks import Callback


class ComputeTime(Callback):
    def __init__(self):
        self.cpu_s_before = 0.0  # totals of the sittings before this one, up to the checkpoint it resumed from
        self.wall_s_before = 0.0
        self._cpu_start = self._wall_start = None

    def on_train_start(self, trainer, pl_module) -> None:
        self._cpu_start, self._wall_start = time.process_time(), time.perf_counter()

    def totals(self) -> tuple[float, float]:
        """(CPU seconds over torch's threads, wall seconds) of the run so far, earlier sittings included."""
        if self._cpu_start is None:
            return self.cpu_s_before, self.wall_s_before
        cpu = (time.process_time() - self._cpu_start) / max(torch.get_num_threads(), 1)
        return self.cpu_s_before + cpu, self.wall_s_before + time.perf_counter() - self._wall_start

    def on_train_batch_end(self, trainer, pl_module, outputs, batch, batch_idx) -> None:
        if trainer.global_step % max(trainer.log_every_n_steps, 1) == 0:
            cpu, wall = self.totals()
            pl_module.log_dict({"compute/cpu_minutes": cpu / 60, "compute/wall_minutes": wall / 60},
                               on_step=True, on_epoch=False)  # fmt: skip

    def state_dict(self) -> dict:
        cpu, wall = self.totals()
        return {"cpu_s": cpu, "wall_s": wall}

    def load_state_dict(self, state_dict: dict) -> None:
        self.cpu_s_before, self.wall_s_before = float(state_dict["cpu_s"]), float(state_dict["wall_s"])


def run_totals(callbacks: list) -> dict:
    """run.json's all-sittings compute, from the run's `ComputeTime` callback ({} without one): a stage resumed across
    sittings is timed whole, where the CLI's own ``train_seconds`` is the last sitting's fit."""
    timer = next((c for c in callbacks if isinstance(c, ComputeTime)), None)
    if timer is None:
        return {}
    cpu, wall = timer.totals()
    return {"wall_seconds_all_sittings": round(wall, 1), "cpu_seconds_all_sittings": round(cpu, 1)}
