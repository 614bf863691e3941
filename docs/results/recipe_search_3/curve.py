"""Run H's in-training val FID (the evaluation callback's 64 fixed val clips, every 1,000 steps) after the trans_dec
cell it starts from, beside the first recipe's trans_enc run, against trans_dec steps: recipe_search_3/curve.png.

    python docs/results/recipe_search_3/curve.py [outputs/recipe_search_3/H]

With a run folder, its csv logs are first merged into in_training_val.csv (committed); without, the plot is
drawn from that file. The trans_dec cell's curve comes from docs/results/ablation_full/cells/, the trans_enc run's
from docs/results/recipe_search/final_run/in_training_val.csv."""

import csv
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HERE = Path(__file__).parent
RESULTS = HERE.parent
TABLE = HERE / "in_training_val.csv"
CELL_STEPS = 15000  # run H starts from the trans_dec cell's step-15,000 weights
COLUMNS = ["step", "val/fid", "val/r_precision_top3", "val/action_accuracy"]


def val_rows(paths) -> dict[int, list[float]]:
    """{step: [step, fid, R-prec top-3, action accuracy]} from Lightning csv logs (steps counted from 1)."""
    rows = {}
    for path in paths:
        for row in csv.DictReader(Path(path).open()):
            if row.get("val/fid"):
                rows[int(row["step"]) + 1] = [int(row["step"]) + 1] + [float(row[c] or "nan") for c in COLUMNS[1:]]
    return rows


if len(sys.argv) > 1:  # the run folder's rows join the committed ones (a machine's folder may hold later sittings only)
    rows = {int(r["step"]): [int(r["step"])] + [float(r[c] or "nan") for c in COLUMNS[1:]]
            for r in csv.DictReader(TABLE.open())} if TABLE.is_file() else {}  # fmt: skip
    rows |= val_rows(sorted(Path(sys.argv[1]).glob("csv/version_*/metrics.csv")))
    with TABLE.open("w", newline="") as f:
        csv.writer(f).writerows([COLUMNS] + [rows[k] for k in sorted(rows)])

run_h = [(int(r["step"]) + CELL_STEPS, float(r["val/fid"])) for r in csv.DictReader(TABLE.open())]
cell = sorted(
    val_rows(sorted((RESULTS / "ablation_full/cells/text_trans_dec_x0_hml263").glob("curve_steps_*.csv"))).values()
)
enc = [
    (int(r["step"]), float(r["val/fid"]))
    for r in csv.DictReader((RESULTS / "recipe_search/final_run/in_training_val.csv").open())
]
fig, ax = plt.subplots(figsize=(7.5, 4))
ax.plot([r[0] for r in cell], [r[1] for r in cell], "o-", ms=3, label="trans_dec cell (issue 43; cosine to 15,000)")
ax.plot(*zip(*run_h, strict=True), "o-", ms=3, label="run H (from the cell's 15,000; cosine restarted, to 25,000 more)")
ax.plot(
    *zip(*enc, strict=True),
    "s--",
    ms=3,
    color="grey",
    label="recipe 1: trans_enc (cosine to 110,000; shipped at 42,000)",
)
ax.axhline(1.004, color="C3", lw=0.8, ls=":", label="shipped model's in-training val FID (1.004, step 42,000)")
ax.set(xscale="linear", yscale="log", xlabel="training step (trans_dec: cell + run H)", ylabel="in-training val FID (64 clips)",
       title="Recipe 3 (trans_dec): in-training val FID", xlim=(0, 100000))  # fmt: skip
ax.legend(fontsize=7)
fig.tight_layout()
fig.savefig(HERE / "curve.png", dpi=110)
print(f"wrote {HERE / 'curve.png'}")
