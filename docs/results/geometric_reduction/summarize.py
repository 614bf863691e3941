"""rules.md's table: each run's val numbers (val/<name>.json) and its training loss terms, averaged over the logged
steps 1,801-2,000 of its first sitting's CSV log. Prints Markdown.
    python docs/results/geometric_reduction/summarize.py"""

import csv
import json
from pathlib import Path

RUNS = {"R0": ("mean (MDM's code; the preset)", "outputs/ablation_full/action_x0_hml263"),
        "R1": ("equation (eq. 3-5 as written)", "outputs/geometric_reduction/r1")}  # fmt: skip
TERMS = ("loss_diffusion", "loss_pos", "loss_vel", "loss_foot")
here = Path(__file__).parent


def loss_terms(run: str) -> dict[str, float]:
    rows = list(csv.DictReader(open(sorted(Path(run).glob("csv/version_*/metrics.csv"))[0])))
    late = [r for r in rows if r["train/loss_diffusion"] and 1800 < int(r["step"]) <= 2000]
    return {t: sum(float(r[f"train/{t}"]) for r in late) / len(late) for t in TERMS}


print("| reduction | FID | accuracy | smoothness | " + " | ".join(TERMS) + " |")
print("|---|---:|---:|---:|" + "---:|" * len(TERMS))
real, fids = None, {}
for name, (label, run) in RUNS.items():
    m = json.loads((here / "val" / f"{name}.json").read_text())
    s, real = m["summary"], m["real"]
    fids[label.split(" (")[0]] = s["fid"][:2]
    cells = [f"{s[k][0]:.3f} ± {s[k][1]:.3f}" for k in ("fid", "accuracy", "smoothness")]
    print(
        f"| {name}: {label} | "
        + " | ".join(cells)
        + " | "
        + " | ".join(f"{v:.4f}" for v in loss_terms(run).values())
        + " |"
    )
print(
    f"| real val clips | {real['fid'][0]:.3f} | {real['accuracy'][0]:.3f} | {real['smoothness'][0]:.3f} |"
    + " |" * len(TERMS)
)
(best, (f1, c1)), (other, (f2, c2)) = sorted(fids.items(), key=lambda kv: kv[1][0])
apart = "do not overlap" if f1 + c1 < f2 - c2 else "overlap"
print(f"\nLower val FID: **{best}** ({f1:.3f} against {f2:.3f} for {other}; the 95% intervals {apart}).")
