"""The final run's in-training val metrics (the evaluation callback's fixed val subset, every 7,000 steps) against
the step, with the rule-S measurements of the full val split marked: final_run/curve.png.

    python docs/results/recipe_search/final_run/curve.py [outputs/train/bandai_text_long]

With a run folder, its csv logs are first collected into in_training_val.csv (committed); without, the plot is
drawn from that file."""

import csv
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HERE = Path(__file__).parent
TABLE = HERE / "in_training_val.csv"
COLUMNS = ["step", "val/fid", "val/r_precision_top3", "val/action_accuracy", "val/diversity", "val/mm_dist"]
# rule S's measurements (docs/results/shipping/rules.md): full val split, 3 replications, DDIM-50, guidance 2
RULE_S = {12000: (2.004, 0.100), 42000: (1.032, 0.088), 63000: (0.990, 0.117), 97000: (0.960, 0.112)}

if len(sys.argv) > 1:
    rows = {}
    for path in sorted(Path(sys.argv[1]).glob("csv/version_*/metrics.csv")):
        for row in csv.DictReader(path.open()):
            if row.get("val/fid"):
                rows[int(row["step"]) + 1] = [int(row["step"]) + 1] + [float(row[c]) for c in COLUMNS[1:]]
    with TABLE.open("w", newline="") as f:
        csv.writer(f).writerows([COLUMNS] + [rows[k] for k in sorted(rows)])

data = list(csv.DictReader(TABLE.open()))
steps = [int(r["step"]) for r in data]
fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4))
ax.plot(steps, [float(r["val/fid"]) for r in data], "o-", label="in training (64 val clips, DDIM-50, one sample each)")
ax.errorbar(list(RULE_S), [v[0] for v in RULE_S.values()], yerr=[v[1] for v in RULE_S.values()], fmt="s",
            color="C3", capsize=3, label="rule S (276 val clips, 3 replications, 95% CI)")  # fmt: skip
ax.axhline(0.068, color="grey", ls="--", label="real val vs train clips (noise floor)")
ax.set(xlabel="training step", ylabel="val FID", title="Final text run: val FID", ylim=(0, 4.5))
ax.legend(fontsize=8)
bx.plot(steps, [float(r["val/r_precision_top3"]) for r in data], "o-", label="R-precision top-3")
bx.plot(steps, [float(r["val/action_accuracy"]) for r in data], "o-", label="action accuracy (label captions)")
bx.set(xlabel="training step", ylabel="in-training val (64 clips)", title="Final text run: text match", ylim=(0.7, 1))
bx.legend(fontsize=8)
for a in (ax, bx):
    a.axvline(42000, color="C2", lw=0.8)
    a.text(42500, a.get_ylim()[0] + 0.02 * (a.get_ylim()[1] - a.get_ylim()[0]), "shipped: 42,000", fontsize=7)
fig.tight_layout()
fig.savefig(HERE / "curve.png", dpi=110)
print(f"{len(data)} evaluations; wrote {HERE / 'curve.png'}")
