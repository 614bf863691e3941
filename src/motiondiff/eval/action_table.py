"""Per-action accuracy and confusion matrices of an action classifier's verdicts on generated and real motion.

"Does the motion do the action it was asked for?" is one number in the evaluation table (`action_accuracy`); this
module breaks it down by action, as a Markdown table (generated next to real, with the clip counts that say how
much each row can be trusted) and a confusion-matrix figure (rows: the asked action, columns: what the
classifier saw), so a reader sees which actions come out as which.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from motiondiff.runtime.atomic import atomic_write


def confusion(asked: Sequence[int], predicted: Sequence[int], num_classes: int) -> np.ndarray:
    """(K, K) counts: row = asked action, column = predicted action."""
    matrix = np.zeros((num_classes, num_classes), dtype=np.int64)
    np.add.at(matrix, (np.asarray(asked, dtype=int), np.asarray(predicted, dtype=int)), 1)
    return matrix


def per_action_rows(
    asked: Sequence[int], generated: Sequence[Sequence[int]], real: Sequence[int] | None, names: Sequence[str]
) -> list[dict]:
    """One row per action that is asked for: clips, generated accuracy pooled over replications, real accuracy
    (NaN where there are no real clips, e.g. held-out descriptions) and the action the generated motions were most
    often mistaken for."""
    asked = np.asarray(asked, dtype=int)
    gen = np.asarray(generated, dtype=int).reshape(-1, len(asked))  # (R, C)
    real = np.full(len(asked), -1) if real is None else np.asarray(real, dtype=int)
    rows = []
    for k in sorted(set(asked[asked >= 0].tolist())):
        clips = asked == k
        got = gen[:, clips].ravel()
        wrong = got[got != k]
        rows.append({
            "action": names[k],
            "clips": int(clips.sum()),
            "generated": float((got == k).mean()),
            "real": float("nan") if (real[clips] < 0).all() else float((real[clips] == k).mean()),
            "mistaken_for": names[int(np.bincount(wrong).argmax())] if wrong.size else "",
        })  # fmt: skip
    return rows


def format_per_action(rows: list[dict], title: str, notes: Sequence[str] = ()) -> str:
    lines = [
        f"### {title}",
        "",
        "| action | clips | generated | real | most often mistaken for |",
        "|---|---:|---:|---:|---|",
    ]
    for r in rows:
        real = "–" if np.isnan(r["real"]) else f"{r['real']:.2f}"
        lines.append(f"| {r['action']} | {r['clips']} | {r['generated']:.2f} | {real} | {r['mistaken_for']} |")
    lines += [""] + [f"- {n}" for n in notes]
    return "\n".join(lines) + "\n"


def plot_confusion(matrix: np.ndarray, names: Sequence[str], path: str | Path, title: str) -> Path:
    """Row-normalised confusion matrix as a PNG (only actions that are asked for or predicted are shown)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    used = np.flatnonzero(matrix.sum(0) + matrix.sum(1))
    m = matrix[np.ix_(used, used)].astype(float)
    share = m / np.maximum(m.sum(1, keepdims=True), 1)
    labels = [names[i] for i in used]
    size = 2.5 + 0.38 * len(used)
    fig, ax = plt.subplots(figsize=(size + 1.5, size))
    im = ax.imshow(share, cmap="Blues", vmin=0, vmax=1)
    ax.set_xticks(range(len(used)), labels, rotation=60, ha="right", fontsize=8)
    ax.set_yticks(range(len(used)), labels, fontsize=8)
    ax.set_xlabel("classified as")
    ax.set_ylabel("asked for")
    ax.set_title(title, fontsize=10)
    for i in range(len(used)):
        for j in range(len(used)):
            if m[i, j]:
                ax.text(j, i, f"{share[i, j]:.2f}".lstrip("0"), ha="center", va="center", fontsize=6,
                        color="white" if share[i, j] > 0.6 else "black")  # fmt: skip
    fig.colorbar(im, ax=ax, fraction=0.046, pad=0.04, label="share of the asked action's motions")
    fig.tight_layout()
    path = Path(path)
    atomic_write(path, lambda tmp: fig.savefig(tmp, dpi=110, format="png"), suffix=".png")
    plt.close(fig)
    return path
