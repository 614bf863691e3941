"""The guidance-scale sweep plot of a Hydra multirun (`python evaluate.py -m guidance=0,1,2.5,4`).

A Hydra callback: when the multirun ends it reads each job's metrics.json and draws FID and R-precision against
the guidance scale (MDM Fig. 4b) into `<sweep dir>/guidance_sweep.png`, with the values in guidance_sweep.md.
`MultirunEnd` is that callback's frame, which the ablation table (`eval.ablation`) shares.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from hydra.experimental.callback import Callback
from omegaconf import DictConfig

from motiondiff.eval import report


def plot_sweep(sweep_dir: str | Path) -> Path:
    """Plot every `*/metrics.json` under a sweep folder; returns the PNG path."""
    sweep_dir = Path(sweep_dir)
    run_dirs = sorted(p.parent for p in sweep_dir.glob("*/metrics.json"))
    points = report.collect_sweep(run_dirs)
    real_file = run_dirs[0] / "metrics.json"
    real = {k: tuple(v) for k, v in json.loads(real_file.read_text()).get("real", {}).items()} or None
    png = report.plot_guidance_sweep(points, sweep_dir / "guidance_sweep.png", real=real,
                                     title="FID and R-precision against the guidance scale")  # fmt: skip
    lines = ["| guidance | FID | R-precision top-3 |", "|---|---|---|"]
    for s, summary in points:
        cells = [report.format_cell(*summary[k][:2]) if k in summary else "–" for k in ("fid", "r_precision_top3")]
        lines.append(f"| {s:g} | {cells[0]} | {cells[1]} |")
    if real:
        cells = [report.format_cell(*real[k][:2]) if k in real else "–" for k in ("fid", "r_precision_top3")]
        lines.append(f"| Real | {cells[0]} | {cells[1]} |")
    report.write_markdown(sweep_dir / "guidance_sweep.md", "\n".join(lines) + "\n")
    print("\n".join(lines))
    print(f"guidance sweep plot: {png}")
    return png


class MultirunEnd(Callback):
    """A Hydra callback that runs ``write(sweep dir)`` when the multirun ends (the sweep's table or plot); a sweep
    with no job's files says so in one line instead."""

    what = ""  # what write makes, for that line

    @staticmethod
    def write(sweep_dir: str | Path) -> Path:
        raise NotImplementedError

    def on_multirun_end(self, config: DictConfig, **kwargs: Any) -> None:
        try:
            self.write(config.hydra.sweep.dir)
        except FileNotFoundError as err:  # every job failed: their own errors were already reported
            print(f"no {self.what}: {err}")


class GuidanceSweepPlot(MultirunEnd):
    what = "guidance sweep plot"
    write = staticmethod(plot_sweep)
