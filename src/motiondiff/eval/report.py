"""Reporting of motion-generation metrics the way MDM reports them (appendix B protocol).

Each metric is computed over R replications (20; MultiModality 5) and reported as mean ± 95% confidence interval,
1.96·σ/√R with σ = np.std(values) (ddof=0, as the official T2M/MDM evaluation code does). This module turns the
per-replication numbers into summaries, Markdown/CSV tables laid out like the paper's tables, a guidance-scale sweep
plot (MDM Fig. 4b), and the small JSON file each run of a Hydra multirun leaves behind for the sweep.

A summary is `{metric: (mean, ci, n)}`; a table's rows are `{method: summary}` ("Real" first, then the models).
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Iterable, Sequence
from pathlib import Path

import numpy as np

from motiondiff.runtime.atomic import atomic_write, finite_or_null

Summary = dict[str, tuple[float, float, int]]

Z_95 = 1.96  # two-sided 95% normal quantile, as in the paper
MISSING = "–"  # en dash for a metric a method has no value for
# columns shown only when some row has them, per protocol: FID against train (where train != the split), the
# smoothness of action-conditioned motion (vvMDM Tab. 1 reports it for action models too; evaluations before it was
# measured have none), smoothness of a representation's own features (vvMDM Fig. 2; models not on HumanML3D features)
OPTIONAL = {"action": {"fid_train", "smoothness"}, "unconstrained": {"smoothness_own"}}

# protocol -> columns (metric key, header, direction); "→" means closer to Real is better, as in the MDM paper
LAYOUTS: dict[str, list[tuple[str, str, str]]] = {
    "text": [  # MDM Table 1 (HumanML3D)
        ("r_precision_top1", "R-Precision top-1", "↑"),
        ("r_precision_top2", "R-Precision top-2", "↑"),
        ("r_precision_top3", "R-Precision top-3", "↑"),
        ("fid", "FID", "↓"),
        ("mm_dist", "MM Dist", "↓"),
        ("diversity", "Diversity", "→"),
        ("multimodality", "MultiModality", "↑"),
        ("action_accuracy", "Action acc. (label caption)", "↑"),  # labelled datasets with an action classifier
        ("action_accuracy_random", "Action acc. (random caption)", "↑"),
    ],
    "action": [  # MDM Table 3 (action-to-motion); Table 4 (UESTC) adds FID against the train clips
        ("fid", "FID", "↓"),
        ("fid_train", "FID (train)", "↓"),  # optional
        ("accuracy", "Accuracy", "↑"),
        ("diversity", "Diversity", "→"),
        ("multimodality", "MultiModality", "→"),
        ("smoothness", "Smoothness", "↑"),  # optional
    ],
    "unconstrained": [  # MDM Table 4; smoothness is vvMDM's addition
        ("fid", "FID", "↓"),
        ("kid", "KID", "↓"),
        ("precision", "Precision", "↑"),
        ("recall", "Recall", "↑"),
        ("diversity", "Diversity", "→"),
        ("smoothness", "Smoothness", "↑"),
        ("smoothness_own", "Smoothness (own features)", "↑"),  # optional: representations other than HumanML3D's
    ],
}


def mean_ci(values: Sequence[float]) -> tuple[float, float]:
    """(mean, 1.96·std/√n) of the replications' values, std with ddof=0; a single value has ci 0."""
    arr = np.asarray(values, dtype=np.float64).ravel()
    if arr.size == 0:
        raise ValueError("mean_ci needs at least one value, got none")
    if np.isnan(arr).any():
        raise ValueError(f"mean_ci got NaN in {int(np.isnan(arr).sum())} of {arr.size} values: {arr.tolist()}")
    if np.isinf(arr).any():
        raise ValueError(f"mean_ci got an infinite value: {arr.tolist()}")
    ci = Z_95 * float(np.std(arr)) / math.sqrt(arr.size) if arr.size > 1 else 0.0
    return float(np.mean(arr)), ci


def summarise(replications: list[dict[str, float]]) -> Summary:
    """Per metric, (mean, ci, n) over the replications that have it (MultiModality is only in the first few)."""
    values: dict[str, list[float]] = {}
    for rep in replications:
        for name, value in rep.items():
            values.setdefault(name, []).append(float(value))
    summary: Summary = {}
    for name, vals in values.items():
        bad = sum(not math.isfinite(v) for v in vals)
        if bad:
            raise ValueError(f"metric {name!r} is NaN or infinite in {bad} of {len(vals)} replication(s)")
        summary[name] = (*mean_ci(vals), len(vals))
    return summary


def _layout(protocol: str) -> list[tuple[str, str, str]]:
    if protocol not in LAYOUTS:
        raise ValueError(f"unknown protocol {protocol!r}; known: {', '.join(LAYOUTS)}")
    return LAYOUTS[protocol]


def _decimals(value: float) -> int:
    """3 decimals, or enough for 3 significant digits when |value| < 0.01 (KID is ~1e-3)."""
    magnitude = abs(value)
    if magnitude == 0 or magnitude >= 0.01 or not math.isfinite(magnitude):
        return 3
    return -math.floor(math.log10(magnitude)) + 2


def format_cell(mean: float, ci: float) -> str:
    """'0.611 ± 0.007'; the CI gets the mean's decimals so the two line up."""
    d = _decimals(mean)
    return f"{mean:.{d}f} ± {ci:.{d}f}"


def format_markdown(
    rows: dict[str, Summary], protocol: str, title: str | None = None, notes: list[str] | None = None
) -> str:
    """A Markdown table: a "Method" column, then the protocol's metric columns; one row per entry, order kept."""
    optional = OPTIONAL.get(protocol, set())
    layout = [c for c in _layout(protocol) if c[0] not in optional or any(c[0] in r for r in rows.values())]
    header = ["Method"] + [f"{head} {arrow}" for _, head, arrow in layout]
    lines = []
    if title:
        lines += [f"### {title}", ""]
    lines.append("| " + " | ".join(header) + " |")
    lines.append("|" + "|".join(["---"] + [":---:"] * len(layout)) + "|")
    for method, summary in rows.items():
        cells = [format_cell(*summary[key][:2]) if key in summary else MISSING for key, _, _ in layout]
        lines.append("| " + " | ".join([method, *cells]) + " |")
    if notes:
        lines.append("")
        lines += [f"- {note}" for note in notes]
    return "\n".join(lines) + "\n"


def write_markdown(path: str | Path, text: str) -> Path:
    return atomic_write(path, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))


def write_csv(path: str | Path, rows: dict[str, Summary], protocol: str) -> Path:
    """One line per method × metric of the protocol (metrics a method lacks are left out); full float precision."""
    layout = _layout(protocol)

    def write(tmp: str) -> None:
        with open(tmp, "w", newline="", encoding="utf-8") as f:
            out = csv.writer(f)
            out.writerow(["method", "metric", "mean", "ci", "n"])
            for method, summary in rows.items():
                for key, _, _ in layout:
                    if key in summary:
                        mean, ci, n = summary[key]
                        out.writerow([method, key, repr(float(mean)), repr(float(ci)), int(n)])

    return atomic_write(path, write)


# guidance sweep panels: metric key, panel title
_SWEEP_PANELS = (("fid", "FID ↓"), ("r_precision_top3", "R-precision top-3 ↑"))


def plot_guidance_sweep(
    points: list[tuple[float, Summary]], path: str | Path, real: Summary | None = None, title: str | None = None
) -> Path:
    """PNG like MDM Fig. 4b: FID and R-precision top-3 against the guidance scale s, with CI error bars and the
    Real value as a dashed line. A panel whose metric no point has is left out."""
    from matplotlib.figure import Figure  # a bare Figure renders with Agg and touches no pyplot global state

    if not points:
        raise ValueError("plot_guidance_sweep needs at least one (guidance, summary) point")
    points = sorted(points, key=lambda p: p[0])
    panels = [(key, name) for key, name in _SWEEP_PANELS if any(key in s for _, s in points)]
    if not panels:
        raise ValueError(f"no point has any of the metrics {[key for key, _ in _SWEEP_PANELS]}")

    fig = Figure(figsize=(4.5 * len(panels), 3.6), layout="constrained")
    axes = fig.subplots(1, len(panels), squeeze=False)[0]
    for ax, (key, name) in zip(axes, panels, strict=True):
        have = [(s, summary[key]) for s, summary in points if key in summary]
        xs = [s for s, _ in have]
        means = [v[0] for _, v in have]
        cis = [v[1] for _, v in have]
        ax.errorbar(xs, means, yerr=cis, marker="o", capsize=3, color="tab:blue", label="model")
        if real is not None and key in real:
            ax.axhline(real[key][0], linestyle="--", color="tab:gray", label="Real")
        ax.set_xlabel("guidance scale s")
        ax.set_title(name)
        ax.grid(alpha=0.3)
        ax.legend(fontsize="small")
    if title:
        fig.suptitle(title)
    return atomic_write(path, lambda tmp: fig.savefig(tmp, dpi=120), suffix=".png")


def write_summary_json(path: str | Path, guidance: float, summary: Summary, extra: dict | None = None) -> Path:
    """{"guidance": s, "summary": {metric: [mean, ci, n]}, **extra}: what `collect_sweep` reads back."""
    data = {
        "guidance": float(guidance),
        "summary": {k: [float(m), float(c), int(n)] for k, (m, c, n) in summary.items()},
    }
    for key, value in (extra or {}).items():
        if key in data:
            raise ValueError(f"extra key {key!r} would overwrite the schema's own field")
        data[key] = finite_or_null(value)  # e.g. a replication's undefined distance: null, never a bare NaN
    text = json.dumps(data, indent=2, allow_nan=False, ensure_ascii=False) + "\n"  # strict JSON: no NaN tokens
    return atomic_write(path, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))


def collect_sweep(run_dirs: Iterable[Path], filename: str = "metrics.json") -> list[tuple[float, Summary]]:
    """Read `filename` from each run dir of a Hydra multirun (dirs without it are skipped: failed or unfinished
    runs) and return (guidance, summary) points sorted by guidance, ready for `plot_guidance_sweep`."""
    points: list[tuple[float, Summary]] = []
    searched = 0
    for run_dir in run_dirs:
        searched += 1
        file = Path(run_dir) / filename
        if not file.is_file():
            continue
        data = json.loads(file.read_text(encoding="utf-8"))
        try:
            summary = {k: (float(m), float(c), int(n)) for k, (m, c, n) in data["summary"].items()}
            points.append((float(data["guidance"]), summary))
        except (KeyError, TypeError, ValueError) as err:
            raise ValueError(
                f"{file}: expected {{'guidance': float, 'summary': {{metric: [mean, ci, n]}}}}: {err!r}"
            ) from err
    if not points:
        raise FileNotFoundError(f"none of the {searched} run dirs has a {filename}")
    return sorted(points, key=lambda p: p[0])
