"""The padding counter: hand-counted frames of a small example, bucketed against random batches, and
`bench/padding.py` on the embedded data writing both rows."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

from motiondiff.bench.padding import compare_batching, markdown, padding_stats

REPO = Path(__file__).resolve().parents[3]


def test_counts_of_a_hand_made_example():
    stats = padding_stats([[0, 1], [2]], np.array([2, 4, 3]))
    assert stats["real_frames"] == 9 and stats["computed_frames"] == 2 * 4 + 3
    assert stats["padded_frames_per_batch"] == 1.0 and stats["real_over_computed"] == pytest.approx(9 / 11)
    assert stats["attention_real_over_computed"] == pytest.approx((4 + 16 + 9) / (2 * 16 + 9))
    with pytest.raises(ValueError, match="no empty batch"):
        padding_stats([[0], []], np.array([2]))


def test_bucketed_batches_compute_fewer_frames_for_the_same_clips():
    lengths = np.random.default_rng(0).integers(40, 197, size=2000)
    result = compare_batching(lengths, batch_size=32, chunk_batches=16, epochs=2)
    random, bucketed = result["random"], result["bucketed"]
    assert random["real_frames"] == bucketed["real_frames"] == 2 * int(lengths.sum())  # every clip, each epoch
    assert bucketed["real_over_computed"] > 0.9 > 0.7 > random["real_over_computed"]
    assert "| bucketed |" in markdown(result)


def test_the_script_reports_the_embedded_data(tmp_path, capsys):
    spec = importlib.util.spec_from_file_location("bench_padding", REPO / "bench" / "padding.py")
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    out = tmp_path / "padding.json"
    assert script.main(["--batch-size", "16", "--epochs", "1", "--out", str(out), "dataset=bandai_mini"]) == 0
    result = json.loads(out.read_text())
    assert result["dataset"] == "bandai_mini" and result["clips"] == 250 and result["batch_size"] == 16
    assert result["bucketed"]["real_over_computed"] > result["random"]["real_over_computed"]
    assert "| random |" in capsys.readouterr().out
