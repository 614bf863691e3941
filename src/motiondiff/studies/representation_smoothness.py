"""vvMDM Fig. 2: how smooth real clips are in each motion representation, measured on that representation's own
temporal features (smoothness, vvMDM eq. 16: 1 = no acceleration).

    python -m motiondiff.studies.representation_smoothness [root=<prepared dataset>] [split=train] [out=<folder>]
        (every key and its default: conf/study/representation_smoothness.yaml)

The default root is the embedded real dataset (data/bandai_mini). Each representation's de-normalised features of
every clip of the split are scored and averaged over clips; the table (and a bar chart) go to `out`
(docs/results/representation_smoothness). The same number for generated motion is evaluate.py's
`smoothness_own` column (unconstrained models of a representation other than HumanML3D's).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from tqdm import tqdm

from motiondiff.data.datamodules import PreparedDataModule, embedded_data_root
from motiondiff.eval.report import write_markdown
from motiondiff.metrics import smoothness
from motiondiff.studies.config import study_config

ORDER = ("jp", "rp6jr", "rpqjr", "rpajr", "rpejr", "rpmjr", "hml263")  # vvMDM Fig. 2's six, then HumanML3D's
OUT = Path(__file__).resolve().parents[3] / "docs" / "results" / "representation_smoothness"


def representation_smoothness(
    root: str | Path, split: str = "train", alpha: float = 1.0, names=ORDER
) -> dict[str, dict]:
    """{representation: {"mean": average over clips, "std": spread over clips, "clips": count, "dims": D}}."""
    out = {}
    for name in tqdm(names, desc="representations", unit="representation"):
        dm = PreparedDataModule(root, batch_size=8, representation=name)
        records = dm.dataset(split).records
        scores = np.array([smoothness(r.motion, alpha) for r in records if len(r.motion) >= 3])
        out[name] = {"mean": float(scores.mean()), "std": float(scores.std()), "clips": int(len(scores)),
                     "dims": int(records[0].motion.shape[1])}  # fmt: skip
    return out


def table(results: dict[str, dict], source: str, split: str) -> str:
    lines = ["# Smoothness of real clips per motion representation (vvMDM Fig. 2)", "",
             f"Data: {source} ({split} split, real motion capture). Smoothness = vvMDM eq. 16 with α = 1 on each "
             "representation's de-normalised features; mean ± std over clips.", "",
             "| representation | features per frame | smoothness | clips |", "|---|---:|---:|---:|"]  # fmt: skip
    for name, r in results.items():
        lines.append(f"| {name} | {r['dims']} | {r['mean']:.4f} ± {r['std']:.4f} | {r['clips']} |")
    lines += ["", "Command: `python -m motiondiff.studies.representation_smoothness`"]
    return "\n".join(lines) + "\n"


def plot(results: dict[str, dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 3.2))
    names = list(results)
    ax.bar(names, [results[n]["mean"] for n in names], yerr=[results[n]["std"] for n in names], color="#4c72b0")
    ax.set_ylabel("smoothness (eq. 16) ↑")
    ax.set_ylim(min(r["mean"] - r["std"] for r in results.values()) * 0.98, 1.0)
    ax.set_title("Real clips per representation (vvMDM Fig. 2)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv: list[str] | None = None) -> None:

    cfg = study_config("representation_smoothness", sys.argv[1:] if argv is None else argv)
    root = Path(cfg.root or embedded_data_root())
    split, out = cfg.split, Path(cfg.out or OUT)
    results = representation_smoothness(root, split)
    out.mkdir(parents=True, exist_ok=True)
    text = table(results, root.name, split)
    write_markdown(out / "README.md", text)
    plot(results, out / "representation_smoothness.png")
    print(text + f"\nwritten to {out}")


if __name__ == "__main__":
    from motiondiff.runtime.scripting import user_errors

    user_errors(main)()
