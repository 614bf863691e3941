"""Issue 43's cells as they stand: one table and one plot of the in-training val FID per ablation table.

    python docs/results/ablation_full/report.py        # writes status.md and curves_<table>.png beside this file

Per cell: its state (not started / training / stopped), the steps reached, the best in-training val FID and the step
it came at, the wall minutes of its sittings (sittings.log) and the CPU minutes training logged
(`compute/cpu_minutes`, from the sittings that had it), and, once the cell has stopped, the test evaluation of its
best-val-FID checkpoint (20 replications) with the convergence mark of the plan (docs/results/ablation_plan.md):
R-precision top-3 ≥ 70 % of the real clips' (text cells) or accuracy ≥ 80 % of real (action cells).
The curves are read from the run folders (outputs/ablation_full/<cell>) where this machine has them and from the
curve_*.csv files cell.sh copies beside the cell's sittings.log after each sitting (other machines' sittings).
"""

from __future__ import annotations

import csv
import json
import re
from datetime import datetime
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from omegaconf import OmegaConf  # noqa: E402

from motiondiff.eval.plateau import plateaued  # noqa: E402

HERE = Path(__file__).parent
RUNS = HERE.parents[2] / "outputs" / "ablation_full"
REPS = ("hml263", "jp", "rp6jr", "rpqjr")
TABLES = {  # the plan's tables: (title, cells as <condition>_<conf/ablation entry>)
    "mdm_backbones": ("MDM Tab. 1: backbones (text, x0, hml263)",
                      ["text_x0_hml263", "text_trans_dec_x0_hml263", "text_trans_dec_token_x0_hml263",
                       "text_gru_x0_hml263", "text_unet_x0_hml263"]),
    "mdm_steps": ("MDM Tab. 6: diffusion steps T (text, trans_enc)",
                  ["text_x0_hml263_t10", "text_x0_hml263_t100", "text_x0_hml263"]),
    "vvmdm_action": ("vvMDM Tab. 1: prediction x representation (action-conditioned)",
                     [f"action_{p}_{r}" for p in ("x0", "eps", "v") for r in REPS]),
    "vvmdm_none": ("vvMDM Tab. 1: prediction x representation (unconditioned)",
                   [f"none_{p}_{r}" for p in ("x0", "eps", "v") for r in REPS]),
}  # fmt: skip
LABELS = {"text_x0_hml263": "trans_enc (T = 1000)"}
PRESET = OmegaConf.load(HERE.parents[2] / "conf" / "experiment" / "ablation_full.yaml")  # the plan's cap and rule
CAP = PRESET.trainer.max_steps
PLATEAU = {k: PRESET.callbacks.plateau[k] for k in ("min_gain", "window", "start", "mode")}
LINE = re.compile(r"^(\S+Z) sitting (starts|ends|stopped)")


def curve(cell: str) -> list[dict]:
    """The logged rows of every sitting of a cell, in step order."""
    files = sorted((RUNS / cell).glob("csv/version_*/metrics.csv")) + sorted(
        (HERE / "cells" / cell).glob("curve_*.csv")
    )
    rows = [r for f in files for r in csv.DictReader(f.read_text().splitlines())]
    return sorted(rows, key=lambda r: int(r["step"]))


def column(rows: list[dict], key: str) -> list[tuple[int, float]]:
    """(step, value) of one logged key, one per step (a run folder and its copies beside sittings.log overlap)."""
    return sorted({int(r["step"]): float(r[key]) for r in rows if r.get(key)}.items())


def wall_minutes(cell: str) -> float | None:
    """Minutes between each 'sitting starts' line of sittings.log and the next line (its end or stop), from the
    last sitting that started from scratch on (earlier ones were thrown away and restarted)."""
    log = HERE / "cells" / cell / "sittings.log"
    if not log.is_file():
        return None
    lines = log.read_text().splitlines()
    fresh = max((i for i, line in enumerate(lines) if "starts" in line and "from scratch" in line), default=0)
    events = [(datetime.fromisoformat(m[1].replace("Z", "+00:00")), m[2])
              for m in map(LINE.match, lines[fresh:]) if m]  # fmt: skip
    spans = [
        (b[0] - a[0]).total_seconds() / 60
        for a, b in zip(events, events[1:], strict=False)
        if a[1] == "starts" and b[1] != "starts"
    ]
    return sum(spans) if spans else None


def machines(cell: str) -> str:
    """The CPUs (with cores and precision where logged) of a cell's sittings, as sittings.log records them."""
    log = HERE / "cells" / cell / "sittings.log"
    lines = log.read_text().splitlines() if log.is_file() else []
    found = [m[1] for m in (re.search(r"sitting starts \((.*), (?:from scratch|ckpt_path=\S*)\)$", x) for x in lines) if m]
    short = [re.sub(r"\((R|TM)\)|Processor |CPU ", "", x) for x in found]
    return "; ".join(dict.fromkeys(short)) or "–"


def cell_row(cell: str) -> dict:
    rows = curve(cell)
    fid = column(rows, "val/fid")
    cpu = column(rows, "compute/cpu_minutes")
    test = HERE / "cells" / cell / "test" / "metrics.json"
    steps = max((int(r["step"]) for r in rows), default=0)
    stopped = steps >= CAP - 1 or plateaued(fid, **PLATEAU)  # logged steps are one short of the checkpoint's
    state = (
        "done" if test.is_file() else "stopped, test to run" if stopped else "in sittings" if rows else "not started"
    )
    return {"cell": cell, "state": state, "steps": steps, "fid": fid,
            "best": min(fid, key=lambda x: x[1]) if fid else None, "wall": wall_minutes(cell),
            "cpu": cpu[-1][1] if cpu else None, "machine": machines(cell), "test": json.loads(test.read_text()) if test.is_file() else None}  # fmt: skip


def converged(row: dict) -> str:
    """The plan's mark from the test evaluation: ✓, 'did not converge in the cap', or '' (not stopped / no rule)."""
    if row["test"] is None:
        return ""
    s, real = row["test"]["summary"], row["test"]["real"]
    key, share = ("r_precision_top3", 0.7) if "r_precision_top3" in s else ("accuracy", 0.8)
    if key not in s or row["cell"].startswith("none_"):
        return "n/a (unconditioned)"
    return "✓" if s[key][0] >= share * real[key][0] else "did not converge in the cap"


def test_cell(row: dict) -> str:
    if row["test"] is None:
        return "–"
    s = row["test"]["summary"]
    key = "r_precision_top3" if "r_precision_top3" in s else "accuracy"
    extra = f"; {key.replace('_', ' ')} {s[key][0]:.3f} ± {s[key][1]:.3f}" if key in s else ""
    return f"FID {s['fid'][0]:.3f} ± {s['fid'][1]:.3f}{extra}"


def fmt(value, spec: str) -> str:
    return "–" if value is None else format(value, spec)


def plot(name: str, title: str, rows: list[dict]) -> str | None:
    drawn = [r for r in rows if r["fid"]]
    if not drawn:
        return None
    fig, ax = plt.subplots(figsize=(7, 4))
    for r in drawn:
        steps, values = zip(*r["fid"], strict=True)
        ax.plot(steps, values, marker="o", ms=3, label=LABELS.get(r["cell"], r["cell"]))
    ax.set(yscale="log", xlabel="training step", ylabel="in-training val FID (64 clips)", title=title)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(HERE / f"curves_{name}.png", dpi=110)
    plt.close(fig)
    return f"curves_{name}.png"


def main() -> None:
    out = ["# Issue 43's cells: where they stand", "",
           "Generated by `python docs/results/ablation_full/report.py`. Rules: [../ablation_plan.md](../ablation_plan.md); "
           "how a cell runs: [README.md](README.md). In-training val FID: the callback's 64 fixed val clips, every "
           "1,000 steps. Test: the best-val-FID checkpoint, 20 replications, run once when the cell has stopped.", ""]  # fmt: skip
    for name, (title, cells) in TABLES.items():
        rows = [cell_row(c) for c in cells]
        out += [f"## {title}", "", "| cell | state | steps | best val FID (logged step) | wall min | CPU min (logged) | "
                "machine | test | converged |", "|---|---|---:|---:|---:|---:|---|---|---|"]  # fmt: skip
        for r in rows:
            best = f"{r['best'][1]:.3f} ({r['best'][0]:,})" if r["best"] else "–"
            out.append(f"| {LABELS.get(r['cell'], r['cell'])} | {r['state']} | {r['steps']:,} | {best} | "
                       f"{fmt(r['wall'], '.0f')} | {fmt(r['cpu'], '.0f')} | {r['machine']} | {test_cell(r)} | {converged(r)} |")  # fmt: skip
        picture = plot(name, title, rows)
        out += ["", f"![{title}]({picture})" if picture else "(no curve yet)", ""]
    (HERE / "status.md").write_text("\n".join(out))
    print(f"wrote {HERE / 'status.md'}")


if __name__ == "__main__":
    main()
