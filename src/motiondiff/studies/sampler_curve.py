"""Fewer sampling steps at matched quality: FID, R-precision, MM-Dist, Diversity and (on labelled data)
action accuracy of one model per sampler and step count, next to the seconds one motion takes, and the cheapest
sampler whose FID is within ``tolerance`` of DDIM-50's and whose action accuracy (label captions) is within
``accuracy_margin`` of the best sampler's: a sampler must not trade "does it do the action" for FID.

    python evaluate.py -m checkpoint=shipped sampler=ddim steps=10,20,50 replications=10 mm_replications=0
    python evaluate.py checkpoint=shipped sampler=ddpm replications=3 mm_replications=0
    python -m motiondiff.studies.sampler_curve runs=[<evaluate run dir>,...] [bench=bench/results/latest.json]
        [tolerance=0.1] [accuracy_margin=0.02] [out=docs/results/sampler_curve]
        (every key and its default: conf/study/sampler_curve.yaml)

Seconds per motion come from the bench's `sample_1_<sampler><steps>_guided_s` (one process, idle machine), not
from the evaluations, which may have run side by side.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from motiondiff.runtime.atomic import finite_or_null, write_json
from motiondiff.runtime.errors import UsageError
from motiondiff.runtime.paths import REPO_DIR
from motiondiff.studies.config import study_config

DEFAULT_OUT = REPO_DIR / "docs" / "results" / "sampler_curve"
METRICS = ("fid", "r_precision_top3", "mm_dist", "diversity")


def load_run(folder: Path) -> dict:
    path = folder / "metrics.json"
    if not path.is_file():
        raise UsageError(f"{folder} has no metrics.json: pass the folders evaluate.py wrote")
    data = json.loads(path.read_text())
    name = data["sampler"]["name"]
    steps = data.get("steps") or data["sampler"].get("steps") or (1000 if name == "ddpm" else 50)
    return {"sampler": name, "steps": int(steps), "label": f"{name.upper()}-{int(steps)}",
            "replications": len(data["replications"]["Model"]), "guidance": data["guidance"],
            "checkpoint": Path(data["checkpoint"]).name,
            **{m: data["summary"][m] for m in METRICS},
            "action_accuracy": data["summary"].get("action_accuracy")}  # fmt: skip


def choose(rows: list[dict], tolerance: float, accuracy_margin: float = 0.02) -> dict:
    """The row with the fewest steps whose FID is within ``tolerance`` (relative) of DDIM-50's and, where every run
    measured it, whose action accuracy is within ``accuracy_margin`` (absolute) of the best run's (none: the most
    accurate of those within the FID tolerance)."""
    reference = next((r for r in rows if r["label"] == "DDIM-50"), None)
    if reference is None:
        raise UsageError("the runs need a DDIM-50 evaluation to compare against")
    limit = reference["fid"][0] * (1 + tolerance)
    ok = [r for r in rows if r["fid"][0] <= limit]
    if all(r.get("action_accuracy") for r in rows):
        best = max(r["action_accuracy"][0] for r in rows)
        ok = [r for r in ok if r["action_accuracy"][0] >= best - accuracy_margin] or [
            max(ok, key=lambda r: r["action_accuracy"][0])]  # fmt: skip
    return min(ok, key=lambda r: (r["steps"], r["fid"][0]))


def _accuracy(r: dict) -> str:
    a = r.get("action_accuracy")
    return "–" if not a else f"{a[0]:.3f} ± {a[1]:.3f}"


def write(out: Path, rows: list[dict], chosen: dict, tolerance: float, times: dict, margin: float = 0.02) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out.parent.mkdir(parents=True, exist_ok=True)
    ref = next(r for r in rows if r["label"] == "DDIM-50")["fid"][0]
    lines = ["# Sampling steps against quality", "",
             f"Model `{rows[0].get('checkpoint', 'shipped')}`, guidance {rows[0]['guidance']:g}; mean ± 95% CI over "
             "each run's replications; seconds: one 196-frame motion with guidance (bench/results/latest.json).", "",
             "| sampler | replications | FID | FID / DDIM-50 | R-precision top-3 | MM-Dist | Diversity | action acc. "
             "| s per motion |", "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]  # fmt: skip
    for r in rows:
        t = times.get(f"sample_1_{r['sampler']}{r['steps']}_guided_s")
        lines.append(f"| {r['label']}{' **(chosen)**' if r is chosen else ''} | {r['replications']} | "
                     f"{r['fid'][0]:.2f} ± {r['fid'][1]:.2f} | {r['fid'][0] / ref:.2f} | "
                     f"{r['r_precision_top3'][0]:.3f} ± {r['r_precision_top3'][1]:.3f} | {r['mm_dist'][0]:.2f} | "
                     f"{r['diversity'][0]:.2f} | {_accuracy(r)} | {'–' if t is None else f'{t:.2f}'} |")  # fmt: skip
    rule = f"the fewest steps with FID within {tolerance:.0%} of DDIM-50's"
    if all(r.get("action_accuracy") for r in rows):
        rule += f" and action accuracy within {margin:g} of the best sampler's"
    lines += ["", f"Chosen: **{chosen['label']}**, {rule}.", ""]
    out.with_suffix(".md").write_text("\n".join(lines))
    write_json(out.with_suffix(".json"), finite_or_null({"rows": rows, "chosen": chosen["label"],
                                                         "tolerance": tolerance, "seconds": times}))  # fmt: skip
    fig, ax = plt.subplots(figsize=(5, 3.5))
    for name in dict.fromkeys(r["sampler"] for r in rows):
        part = sorted((r for r in rows if r["sampler"] == name), key=lambda r: r["steps"])
        ax.errorbar([r["steps"] for r in part], [r["fid"][0] for r in part], yerr=[r["fid"][1] for r in part],
                    marker="o", capsize=3, label=name.upper())  # fmt: skip
    ax.axhline(ref * (1 + tolerance), color="grey", ls="--", lw=1, label=f"DDIM-50 FID + {tolerance:.0%}")
    ax.set_xscale("log")
    ax.set_xlabel("sampling steps")
    ax.set_ylabel("FID (lower is better)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out.with_suffix(".png"), dpi=120)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:

    cfg = study_config("sampler_curve", argv if argv is not None else sys.argv[1:])
    rows = sorted((load_run(Path(p)) for p in cfg.runs), key=lambda r: (r["sampler"], r["steps"]))
    bench = Path(cfg.bench or REPO_DIR / "bench" / "results" / "latest.json")
    times = (
        {k: v for k, v in json.loads(bench.read_text()).items() if k.startswith("sample_1_")} if bench.is_file() else {}
    )
    chosen = choose(rows, cfg.tolerance, cfg.accuracy_margin)
    out = Path(cfg.out or DEFAULT_OUT)
    write(out, rows, chosen, cfg.tolerance, times, cfg.accuracy_margin)
    print(out.with_suffix(".md").read_text())
    return 0


if __name__ == "__main__":
    from motiondiff.runtime.scripting import user_errors

    sys.exit(user_errors(main)())
