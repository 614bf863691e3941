"""Issue 43's cells as they stand: one table and one plot of the in-training val FID per ablation table.

    python docs/results/ablation_full/report.py     # writes ../ablation.md and curves_<table>.png beside this file

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
OUT = HERE.parent / "ablation.md"
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
LABELS = {
    "text_x0_hml263": "trans_enc (T = 1000)",
    "text_trans_dec_x0_hml263": "trans_dec",
    "text_trans_dec_token_x0_hml263": "trans_dec + token",
    "text_gru_x0_hml263": "gru",
    "text_unet_x0_hml263": "unet",
    "text_x0_hml263_t10": "T = 10",
    "text_x0_hml263_t100": "T = 100",
}
LABELS |= {f"{c}_{p}_{r}": f"{p.replace('eps', 'ε')} · {r}" for c in ("action", "none") for p in ("x0", "eps", "v")
           for r in REPS}  # fmt: skip
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


def machines(cell: str) -> dict[str, dict[str, list]]:
    """The CPU of a cell's sittings with torch's threads and the precision of each, as sittings.log records them
    (lines before 2026-12-06 21:15 UTC name the CPU only: those sittings ran torch's default of one thread per core,
    in fp32, on CPUs without native bf16)."""
    log = HERE / "cells" / cell / "sittings.log"
    lines = log.read_text().splitlines() if log.is_file() else []
    pattern = r"sitting starts \((.*?)(?:, (\d+) cores, (\d+) torch threads, (\S+))?, (?:from scratch|ckpt_path=\S*)\)$"
    cpus: dict[str, dict[str, list]] = {}
    for m in filter(None, (re.search(pattern, line) for line in lines)):
        cpu = re.sub(r"\((R|TM)\)|Processor |CPU ", "", m[1])
        seen = cpus.setdefault(cpu, {"threads": [], "precision": []})
        threads, precision = (m[3], m[4].replace("32-true", "fp32")) if m[2] else (None, "fp32")
        for key, value in (("threads", threads), ("precision", precision)):
            if value not in seen[key]:
                seen[key].append(value)
    return cpus


def machine_text(cpus: dict[str, dict[str, list]]) -> str:
    """'<CPU>, <precision>, torch threads: <n>[, then <m>]' per CPU of `machines`, '–' for none."""
    texts = [f"{cpu}, {'/'.join(v['precision'])}, torch threads: {', then '.join(x or 'one per core' for x in v['threads'])}"
             for cpu, v in cpus.items()]  # fmt: skip
    return "; ".join(texts) or "–"


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
            "cpu": cpu[-1][1] if cpu else None, "machines": machines(cell), "test": json.loads(test.read_text()) if test.is_file() else None}  # fmt: skip


CONVERGED = {"text": ("r_precision_top3", 0.7), "action": ("accuracy", 0.8)}  # the plan's share of the real clips'


def condition(cell: str) -> str:
    """text, action or none: a cell's name starts with its condition."""
    return cell.split("_")[0]


def converged(row: dict) -> str:
    """The plan's mark from the test evaluation: ✓, 'did not converge in the cap', or '' (not stopped / no rule)."""
    if row["test"] is None:
        return ""
    if condition(row["cell"]) not in CONVERGED:
        return "n/a (unconditioned)"
    key, share = CONVERGED[condition(row["cell"])]
    s, real = row["test"]["summary"], row["test"]["real"]
    if key not in s:
        return "–"
    return "✓" if s[key][0] >= share * real[key][0] else "did not converge in the cap"


def metric(row: dict, key: str, source: str = "summary") -> str:
    """'mean ± 95 % CI' of one test metric (source 'real' for the real clips' row), '–' where absent."""
    if row["test"] is None or key not in row["test"][source]:
        return "–"
    mean, ci = row["test"][source][key][:2]
    return f"{mean:.3f} ± {ci:.3f}" if abs(mean) >= 0.01 else f"{mean:.1e} ± {ci:.0e}"


def fmt(value, spec: str) -> str:
    return "–" if value is None else format(value, spec)


REP_COLOURS = dict(zip(REPS, ("tab:blue", "tab:orange", "tab:green", "tab:red"), strict=True))
PREDICTION_LINES = {"x0": "-", "eps": ":", "v": "--"}


def vvmdm_parts(cell: str) -> tuple[str, str] | None:
    """(prediction, representation) of a vvMDM Tab. 1 cell (<condition>_<prediction>_<representation>), else None."""
    parts = cell.split("_")
    if len(parts) == 3 and parts[1] in PREDICTION_LINES and parts[2] in REP_COLOURS:
        return parts[1], parts[2]
    return None


def line_style(cell: str, index: int) -> dict:
    """vvMDM's 12 cells: the colour says the representation, the line the prediction (12 lines outrun one palette);
    other tables: the palette in order."""
    parts = vvmdm_parts(cell)
    if parts is not None:
        return {"color": REP_COLOURS[parts[1]], "linestyle": PREDICTION_LINES[parts[0]]}
    return {"color": f"C{index}"}


def plot(name: str, title: str, rows: list[dict]) -> str | None:
    drawn = [r for r in rows if r["fid"]]
    if not drawn:
        return None
    fig, ax = plt.subplots(figsize=(7, 4))
    for i, r in enumerate(drawn):
        steps, values = zip(*r["fid"], strict=True)
        ax.plot(steps, values, marker="o", ms=3, label=LABELS.get(r["cell"], r["cell"]), **line_style(r["cell"], i))
    ax.set(yscale="log", xlabel="training step", ylabel="in-training val FID (64 clips)", title=title)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(HERE / f"curves_{name}.png", dpi=110)
    plt.close(fig)
    return f"curves_{name}.png"


SCORES = {  # the test metrics beside FID and smoothness, per condition: the papers' own columns
    "text": [("r_precision_top3", "R-prec top-3 ↑")],
    "action": [("accuracy", "action acc. ↑")],
    "none": [("kid", "KID ↓"), ("precision", "precision ↑"), ("recall", "recall ↑")],
}


def table(rows: list[dict]) -> list[str]:
    """One ablation table (its cells share a condition): the real clips' row, one per representation where they
    differ (each cell's test scores the real clips through its own representation and judges convergence against
    them), then every cell."""
    scores = SCORES[condition(rows[0]["cell"])]
    names = " | ".join(name for _, name in scores)
    out = [f"| cell | state | steps | best val FID (step) | wall min | CPU min | machine | FID ↓ | {names} | smoothness → "
           "| converged |", "|---|---|---:|---:|---:|---:|---|" + "---|" * (len(scores) + 3)]  # fmt: skip

    def measured(r: dict, source: str = "summary") -> str:
        keys = ["fid", *(key for key, _ in scores), "smoothness"]
        return " | ".join(metric(r, key, source) for key in keys)

    real_rows: dict[str, list[str]] = {}  # each cell scores the real clips through its own representation
    for r in rows:
        if r["test"]:
            group = real_rows.setdefault(measured(r, "real"), [])
            parts = vvmdm_parts(r["cell"])
            whose = parts[1] if parts else LABELS.get(r["cell"], r["cell"])
            if whose not in group:
                group.append(whose)
    for values, cells in real_rows.items():
        whose = f" ({', '.join(cells)} cells)" if len(real_rows) > 1 else ""
        out.append(f"| **real test clips**{whose} | | | | | | | {values} | |")
    for r in rows:
        best = f"{r['best'][1]:.3f} ({r['best'][0]:,})" if r["best"] else "–"
        out.append(f"| {LABELS.get(r['cell'], r['cell'])} | {r['state']} | {r['steps']:,} | {best} | "
                   f"{fmt(r['wall'], '.0f')} | {fmt(r['cpu'], '.0f')} | {machine_text(r['machines'])} | {measured(r)} | "
                   f"{converged(r)} |")  # fmt: skip
        account = HERE / "cells" / r["cell"] / "test_leading_static" / "metrics.json"
        if account.is_file():  # an ε cell's second test: eps_fix's S3 sampling, for issue 43 point 2's account
            s = {**r, "test": json.loads(account.read_text())}
            out.append(f"| ↳ same checkpoint, MDM's DDIM steps + static x̂0 clip | | | | | | | {measured(s)} | "
                       f"{converged(s)} |")  # fmt: skip
    return out


def opening(all_rows: dict[str, list[dict]]) -> list[str]:
    """What was trained, for how long, on what, and the verdict per table (verdicts.yaml, written by hand once a
    table has its cells; 'pending' until then)."""
    verdicts = OmegaConf.load(HERE / "verdicts.yaml") if (HERE / "verdicts.yaml").is_file() else {}
    by_cell = {r["cell"]: r for table_rows in all_rows.values() for r in table_rows}  # T = 1000 is trans_enc
    rows = list(by_cell.values())
    done = [r for r in rows if r["state"] == "done"]
    hours = sum(r["wall"] or 0 for r in rows) / 60
    cpus = "; ".join(dict.fromkeys(cpu for r in rows for cpu in r["machines"]))
    out = [f"**What was trained.** {len(done)} of {len(rows)} cells have stopped and been tested; "
           f"{sum(r['steps'] for r in rows):,} training steps and {hours:.1f} h of sittings so far, on {cpus or '–'}. "
           "Every cell is the small model of `bandai_text_long` on the full Bandai set (real mocap; its text captions "
           "are generated from the action and style labels; the hml263 cells also train on every clip's left-right "
           "mirror, the jp, rp6jr and rpqjr cells do not: the plan's note of 2026-12-07; the ε cells weight the "
           "geometric terms by ᾱ_t and sample with MDM's DDIM steps, never t = 999, where the x0 and v cells keep MDM's "
           "unweighted terms and uniform steps: [eps_fix/rules.md](eps_fix/rules.md), amendment 2; the first ε recipe's "
           "curves are in [eps_fix/t0/](eps_fix/t0/); why ε · hml263 makes no motion at this width, measured: its "
           "128-wide output cannot predict noise in 263 features, amendment 3 there), trained until its in-training "
           "val FID stopped improving "
           f"by {PLATEAU['min_gain']:.0%} over {PLATEAU['window']:,} steps (from step {PLATEAU['start']:,}) or to the "
           f"{CAP:,}-step cap; each is scored once on the test split with its best-val-FID checkpoint (20 "
           "replications, mean ± 95 % CI, DDIM-50, guidance 2). Rules: [ablation_plan.md](ablation_plan.md).", "",
           "| table | cells tested | steps per tested cell | verdict: does the paper's claim hold here? |",
           "|---|---|---|---|"]  # fmt: skip
    for name, (title, _) in TABLES.items():
        table_rows = all_rows[name]
        tested = [r for r in table_rows if r["state"] == "done"]
        steps = ", ".join(f"{r['steps'] + 1:,}" for r in tested) or "–"
        verdict = verdicts.get(name) or f"pending ({len(tested)} of {len(table_rows)} cells tested)"
        out.append(f"| [{title}](#{anchor(title)}) | {len(tested)} / {len(table_rows)} | {steps} | {verdict} |")
    return out + ["", "GuidedMotion against MDM and its Tab. 4 ablation (issue 43 point 3) are measured by `make "
                  "guided-compare`: [guidedmotion/comparison_mirror.md](guidedmotion/comparison_mirror.md), its "
                  "verdict in [../guidedmotion.md](../guidedmotion.md).", ""]  # fmt: skip


def anchor(title: str) -> str:
    """GitHub's heading anchor: lower case, punctuation dropped, spaces to hyphens."""
    return re.sub(r"[^a-z0-9 _-]", "", title.lower()).replace(" ", "-")


def main() -> None:
    all_rows = {name: [cell_row(c) for c in cells] for name, (_, cells) in TABLES.items()}
    out = ["# Ablations at a plateau on the full Bandai set (issue 43)", "",
           "Generated by `python docs/results/ablation_full/report.py` from the cells' run folders and the files "
           "`cell.sh` keeps in [ablation_full/cells/](ablation_full/cells/); how a cell runs: "
           "[ablation_full/README.md](ablation_full/README.md). The earlier, barely trained table on the 252 "
           "embedded clips: [ablation_embedded.md](ablation_embedded.md).", ""]  # fmt: skip
    out += opening(all_rows)
    for name, (title, _) in TABLES.items():
        out += [f"## {title}", ""] + table(all_rows[name])
        picture = plot(name, title, all_rows[name])
        out += ["", f"![{title}](ablation_full/{picture})" if picture else "(no curve yet)", ""]
    out += ["State: *in sittings* (training, resumed across sittings), *stopped, test to run*, *done* (tested). "
            "Steps and best val FID are the logged ones (one short of the checkpoint's step). Wall minutes come from "
            "each cell's sittings.log, CPU minutes from `compute/cpu_minutes` where the sittings logged it (the "
            "process's CPU time over its threads). The curves are the in-training val FID on the evaluation "
            "callback's 64 fixed val clips, every 1,000 steps. Smoothness: 1 is perfectly smooth; the real clips' "
            "value is the target.", ""]  # fmt: skip
    (OUT).write_text("\n".join(out))
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
