"""The sampler trade-off report: reading evaluate.py's metrics.json, and choosing the fewest steps whose FID stays
within the tolerance of DDIM-50's."""

from __future__ import annotations

import json

import pytest

from motiondiff.cli.common import UsageError
from motiondiff.studies.sampler_curve import choose, load_run, main


def _run(folder, name, steps, fid, top_steps=None, accuracy=None):
    folder.mkdir(parents=True)
    metric = {"fid": [fid, 0.5, 3], "r_precision_top3": [0.5, 0.02, 3], "mm_dist": [6.0, 0.1, 3],
              "diversity": [13.0, 0.4, 3]}  # fmt: skip
    if accuracy is not None:
        metric["action_accuracy"] = [accuracy, 0.01, 3]
    data = {"guidance": 4.0, "summary": metric, "checkpoint": "/x/model.safetensors", "steps": top_steps,
            "sampler": {"name": name, "steps": steps, "eta": 0.0}, "replications": {"Model": [{}, {}, {}]}}  # fmt: skip
    (folder / "metrics.json").write_text(json.dumps(data))
    return folder


def test_steps_come_from_the_override_then_the_sampler_then_its_default(tmp_path):
    assert load_run(_run(tmp_path / "a", "ddim", 50, 10.0, top_steps=10))["label"] == "DDIM-10"
    assert load_run(_run(tmp_path / "b", "ddim", 20, 10.0))["label"] == "DDIM-20"
    assert load_run(_run(tmp_path / "c", "ddpm", None, 10.0))["label"] == "DDPM-1000"


def test_the_cheapest_sampler_within_the_tolerance_is_chosen(tmp_path):
    rows = [load_run(_run(tmp_path / n, s, k, f)) for n, s, k, f in
            (("a", "ddim", 10, 13.0), ("b", "ddim", 20, 10.9), ("c", "ddim", 50, 10.0), ("d", "ddpm", None, 9.0))]  # fmt: skip
    assert choose(rows, 0.1)["label"] == "DDIM-20"
    assert choose(rows, 0.5)["label"] == "DDIM-10"
    assert choose(rows, 0.0)["label"] == "DDIM-50"  # DDPM-1000 is better but never cheaper
    with pytest.raises(UsageError, match="DDIM-50"):
        choose([r for r in rows if r["label"] != "DDIM-50"], 0.1)


def test_a_sampler_that_loses_action_accuracy_is_not_chosen(tmp_path):
    """FID alone picked DDIM-50 once, although DDPM made the asked action more often: action accuracy counts too."""
    rows = [load_run(_run(tmp_path / n, s, k, f, accuracy=a)) for n, s, k, f, a in
            (("a", "ddim", 20, 10.5, 0.50), ("b", "ddim", 50, 10.0, 0.61), ("c", "ddim", 100, 10.0, 0.70),
             ("d", "ddpm", None, 10.2, 0.71))]  # fmt: skip
    assert choose(rows, 0.1)["label"] == "DDIM-100"
    assert choose(rows, 0.1, accuracy_margin=0.2)["label"] == "DDIM-50"
    assert choose(rows, 0.1, accuracy_margin=0.3)["label"] == "DDIM-20"
    # the most accurate sampler misses the FID tolerance: the most accurate of those that meet it
    assert (
        choose(rows[:2] + [load_run(_run(tmp_path / "e", "ddpm", None, 30.0, accuracy=0.9))], 0.1)["label"] == "DDIM-50"
    )


def test_report_is_written_with_the_chosen_row(tmp_path):
    runs = [_run(tmp_path / n, "ddim", k, f) for n, k, f in (("a", 10, 13.0), ("b", 20, 10.5), ("c", 50, 10.0))]
    main([f"runs=[{','.join(map(str, runs))}]", f"bench={tmp_path / 'none.json'}", f"out={tmp_path / 'curve'}"])
    assert "DDIM-20 **(chosen)**" in (tmp_path / "curve.md").read_text()
    assert json.loads((tmp_path / "curve.json").read_text())["chosen"] == "DDIM-20"
    assert (tmp_path / "curve.png").stat().st_size > 0
