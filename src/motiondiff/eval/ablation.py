"""The summary table of an ablation multirun (the command: `COMMAND` below).

Each cell's run folder holds metrics.json (evaluate.py's protocol at the end of training) and run.json (steps
trained, the cell's labels). When the multirun ends, `AblationTable` writes `<sweep dir>/ablation.md`: one table per
study (prediction x representation; backbone), mean ± 95% CI over the replications, with the Real row, the
training steps each cell reached in the shared time budget, and the command that made it.

    python -m motiondiff.eval.ablation <sweep dir>      # rebuild the table from the run folders
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from motiondiff.eval import report
from motiondiff.eval.sweep import MultirunEnd
from motiondiff.runtime.atomic import atomic_write

TITLES = {
    "prediction_representation": "Prediction x representation (trans_enc backbone)",
    "backbone": "Backbone (x0 prediction, hml263 features)",
}
COMMAND = "python train.py -m experiment=ablation_bandai 'ablation=glob(*,exclude=[*_rpqjr,*_t10,*_t100,*_token_*])'"
# vvMDM eq. 16 (closer to 1 = smoother), on the HumanML3D features of every cell's samples (one space for all)
EXTRA = (("smoothness", "Smoothness"),)


def collect(sweep_dir: str | Path) -> list[dict]:
    """One entry per finished cell: {"study", "steps", "summary", "real", "wall_s"} (unfinished cells skipped)."""
    cells = []
    for metrics in sorted(Path(sweep_dir).glob("*/metrics.json")):
        run = metrics.parent / "run.json"
        if not run.is_file():
            continue
        data, meta = json.loads(metrics.read_text()), json.loads(run.read_text())
        if not meta.get("study"):
            continue
        cells.append({
            "study": meta["study"],
            "steps": int(meta["train_steps"]),
            "summary": {k: tuple(v) for k, v in data["summary"].items()},
            "real": {k: tuple(v) for k, v in data.get("real", {}).items()},
            "wall_s": float(data.get("wall_s", 0.0)),
        })  # fmt: skip
    return cells


def _label(study: dict, table: str) -> str:
    if table == "backbone":
        return study["backbone"]
    return f"{study['prediction']} · {study['representation']}"


def format_tables(cells: list[dict], notes: list[str] | None = None) -> str:
    if not cells:
        raise FileNotFoundError("no finished ablation cell (metrics.json + run.json) in the sweep folder")
    parts = ["# Ablation on the embedded Bandai data", "", f"Command: `{COMMAND}`", ""]
    # The Real row is the same clips for every cell; take it from a cell that reads them natively (hml263).
    real = next((c["real"] for c in cells if c["study"].get("representation") == "hml263"), cells[0]["real"])
    for table, title in TITLES.items():
        rows = {f"{_label(c['study'], table)} ({c['steps']:,} steps)": c["summary"] for c in cells
                if table in c["study"].get("tables", [])}  # fmt: skip
        if not rows:
            continue
        text = report.format_markdown({"Real": real, **rows}, "text", title=title)
        extra = [f"| {name} | " + " | ".join(report.format_cell(*s[k][:2]) if k in s else "–" for k, _ in EXTRA)
                 + " |" for name, s in {"Real": real, **rows}.items()]  # fmt: skip
        parts += [text, "| Method | " + " | ".join(h for _, h in EXTRA) + " |", "|---|:---:|", *extra, ""]
    parts += [f"- {n}" for n in notes or []]
    return "\n".join(parts) + "\n"


PANELS = (("fid", "FID ↓"), ("r_precision_top3", "R-precision top-3 ↑"))


def plot(cells: list[dict], path: str | Path) -> Path:
    """One row per study, FID and R-precision top-3 per cell as bars with 95% CIs, Real as a dashed line."""
    from matplotlib.figure import Figure  # a bare Figure renders with Agg and touches no pyplot global state

    studies = [t for t in TITLES if any(t in c["study"].get("tables", []) for c in cells)]
    real = next((c["real"] for c in cells if c["study"].get("representation") == "hml263"), cells[0]["real"])
    fig = Figure(figsize=(10, 3.2 * len(studies)), layout="constrained")
    axes = fig.subplots(len(studies), len(PANELS), squeeze=False)
    for row, table in zip(axes, studies, strict=True):
        members = [c for c in cells if table in c["study"].get("tables", [])]
        labels = [_label(c["study"], table) for c in members]
        for ax, (key, name) in zip(row, PANELS, strict=True):
            means = [c["summary"][key][0] for c in members]
            cis = [c["summary"][key][1] for c in members]
            ax.barh(labels, means, xerr=cis, capsize=3, color="tab:blue", alpha=0.8)
            if key in real:
                ax.axvline(real[key][0], linestyle="--", color="tab:gray", label="Real")
                ax.legend(fontsize="small")
            ax.invert_yaxis()
            ax.set_title(f"{TITLES[table]}: {name}", fontsize="small")
            ax.grid(alpha=0.3, axis="x")
    return atomic_write(path, lambda tmp: fig.savefig(tmp, dpi=110), suffix=".png")


def write_table(sweep_dir: str | Path, notes: list[str] | None = None) -> Path:
    sweep_dir = Path(sweep_dir)
    cells = collect(sweep_dir)
    text = format_tables(cells, notes)
    path = report.write_markdown(sweep_dir / "ablation.md", text)
    png = plot(cells, sweep_dir / "ablation.png")
    print(text)
    print(f"ablation table: {path}; plot: {png}")
    return path


class AblationTable(MultirunEnd):
    what = "ablation table"
    write = staticmethod(write_table)


if __name__ == "__main__":
    write_table(sys.argv[1])
