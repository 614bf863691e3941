"""Reporting of evaluation metrics: mean ± 95% CI, paper-style tables, CSV, guidance-sweep plot and its JSON inputs."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest

from motiondiff.eval.report import (
    LAYOUTS,
    collect_sweep,
    format_markdown,
    mean_ci,
    plot_guidance_sweep,
    summarise,
    write_csv,
    write_markdown,
    write_summary_json,
)


def test_mean_ci_hand_case():
    mean, ci = mean_ci([1, 2, 3, 4])
    assert mean == 2.5
    assert ci == pytest.approx(1.96 * math.sqrt(1.25) / 2)  # np.std with ddof=0 is sqrt(1.25)
    assert mean_ci([0.7]) == (0.7, 0.0)


def test_nan_and_empty_raise():
    with pytest.raises(ValueError, match="NaN"):
        mean_ci([1.0, float("nan")])
    with pytest.raises(ValueError, match="none"):
        mean_ci([])
    with pytest.raises(ValueError, match="'fid'.*NaN"):
        summarise([{"fid": 1.0}, {"fid": float("nan")}])


def test_summarise_uses_the_replications_that_have_a_metric():
    reps = [{"fid": float(i), **({"multimodality": 2.0 + i} if i < 2 else {})} for i in range(4)]
    s = summarise(reps)
    assert s["fid"][2] == 4 and s["multimodality"][2] == 2
    assert s["fid"][:2] == pytest.approx(mean_ci([0, 1, 2, 3]))
    assert s["multimodality"][:2] == pytest.approx((2.5, 1.96 * 0.5 / math.sqrt(2)))


ROWS = {
    "Real": {"r_precision_top3": (0.797, 0.002, 20), "fid": (0.002, 0.0001, 20), "diversity": (9.503, 0.065, 20)},
    "MDM": {"r_precision_top3": (0.611, 0.007, 20), "fid": (0.544, 0.044, 20), "diversity": (9.559, 0.086, 20)},
}


def test_markdown_table():
    text = format_markdown(ROWS, "text", title="HumanML3D", notes=["20 replications", "DDPM 1000 steps"])
    lines = text.splitlines()
    assert lines[0] == "### HumanML3D"
    header = next(line for line in lines if line.startswith("| Method"))
    assert "R-Precision top-3 ↑" in header and "FID ↓" in header and "Diversity →" in header
    assert header.count("|") == len(LAYOUTS["text"]) + 2
    real, mdm = (next(line for line in lines if line.startswith(f"| {m} ")) for m in ROWS)
    assert lines.index(real) < lines.index(mdm)  # row order kept
    assert "0.611 ± 0.007" in mdm and "0.544 ± 0.044" in mdm and "9.559 ± 0.086" in mdm
    assert "0.00200 ± 0.00010" in real  # small values get more digits
    assert "–" in mdm  # no multimodality
    assert "- 20 replications" in lines
    with pytest.raises(ValueError, match="unknown protocol"):
        format_markdown(ROWS, "nope")


def test_write_markdown(tmp_path):
    path = write_markdown(tmp_path / "t.md", format_markdown(ROWS, "action"))
    assert "| Method | FID ↓ | Accuracy ↑ | Diversity → | MultiModality → |" in path.read_text(encoding="utf-8")
    # an action model's smoothness (vvMDM Tab. 1) is a column as soon as a row has it
    smooth = {m: {**r, "smoothness": (0.5, 0.01, 2)} for m, r in ROWS.items()}
    assert "| MultiModality → | Smoothness ↑ |" in format_markdown(smooth, "action")


def test_csv_round_trip(tmp_path):
    path = write_csv(tmp_path / "metrics.csv", ROWS, "text")
    with open(path, newline="", encoding="utf-8") as f:
        read = list(csv.DictReader(f))
    assert len(read) == 6  # 2 methods x 3 metrics present
    assert list(read[0]) == ["method", "metric", "mean", "ci", "n"]
    back = {(r["method"], r["metric"]): (float(r["mean"]), float(r["ci"]), int(r["n"])) for r in read}
    assert back == {(m, k): v for m, s in ROWS.items() for k, v in s.items()}


def _assert_png_not_blank(path):
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    from matplotlib.image import imread

    img = imread(path)
    assert img.ndim == 3 and np.ptp(img.reshape(-1, img.shape[-1]), axis=0).max() > 0


def test_plot_guidance_sweep(tmp_path):
    points = [
        (s, {"fid": (1.0 / s + 0.2, 0.05, 20), "r_precision_top3": (0.6 + 0.02 * s, 0.007, 20)})
        for s in (5.0, 1.0, 2.5)
    ]
    path = plot_guidance_sweep(points, tmp_path / "sweep.png", real=ROWS["Real"], title="guidance sweep")
    _assert_png_not_blank(path)
    only_fid = plot_guidance_sweep([(s, {"fid": v["fid"]}) for s, v in points], tmp_path / "fid.png")
    _assert_png_not_blank(only_fid)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fid.png", "sweep.png"]  # no temp files left behind


def test_summary_json_round_trip(tmp_path):
    scales = [2.5, 0.0, 7.5]  # written in non-sorted order
    dirs = []
    for i, s in enumerate(scales):
        run = tmp_path / "multirun" / str(i)
        run.mkdir(parents=True)
        write_summary_json(
            run / "metrics.json", s, {"fid": (1.0 + s, 0.1, 20), "kid": (0.001, 0.0002, 20)}, {"seed": i}
        )
        dirs.append(run)
    empty = tmp_path / "multirun" / "failed"
    empty.mkdir()
    points = collect_sweep([*dirs, empty])
    assert [s for s, _ in points] == sorted(scales)
    assert points[1][1] == {"fid": (3.5, 0.1, 20), "kid": (0.001, 0.0002, 20)}
    with pytest.raises(FileNotFoundError, match="none of the 1 run dirs"):
        collect_sweep([empty])
    with pytest.raises(ValueError, match="overwrite"):
        write_summary_json(tmp_path / "x.json", 1.0, {}, {"summary": 1})
