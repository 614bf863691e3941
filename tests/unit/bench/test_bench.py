"""The benchmark's measuring tools: FLOP counts against hand counts, repeat bookkeeping, peak memory that sees an
allocation, chains timed over their first steps, and `bench/run.py --quick` writing every key the issue names."""

from __future__ import annotations

import importlib.util
import json
import re
from pathlib import Path

import torch

from motiondiff.bench.flops import count_flops, matmul_flops_per_s
from motiondiff.bench.timing import PeakMemory, median_seconds

REPO = Path(__file__).resolve().parents[3]


def test_flops_of_a_linear_layer_are_two_per_multiply_add():
    layer = torch.nn.Linear(64, 32, bias=False)
    x = torch.randn(10, 64)
    assert count_flops(lambda: layer(x)) == 2 * 10 * 64 * 32
    ref = matmul_flops_per_s(16, 8, 4, repeats=1)
    assert ref["shape"] == [16, 8, 4] and ref["flops_per_s"] == 2 * 16 * 8 * 4 / ref["median_s"]


def test_median_seconds_warms_up_then_times_each_repeat():
    calls = []
    result = median_seconds(lambda: calls.append(1), repeats=4, warmup=2)
    assert len(calls) == 6 and len(result["times_s"]) == 4
    assert result["median_s"] == sorted(result["times_s"])[1] / 2 + sorted(result["times_s"])[2] / 2


def test_peak_memory_sees_an_allocation_that_is_freed_again():
    with PeakMemory() as mem:
        start = mem.peak_bytes
        block = torch.ones(64 * 2**20 // 4 * 4)  # 256 MB, touched
        del block
    assert mem.peak_bytes - start > 200 * 2**20


def test_a_long_chain_is_timed_over_its_first_steps():
    from motiondiff.bench.workloads import sampling
    from motiondiff.model_files.loading import load_model as load_module

    module = load_module(REPO / "checkpoints" / "models" / "bandai_mini_text_cpu.safetensors")
    calls = []
    forward = module.denoiser.forward
    module.denoiser.forward = lambda *a, **k: calls.append(1) or forward(*a, **k)
    run, total, done = sampling(module, 1, 10, "ddpm", None, guidance=2.5, timed_steps=3)
    run()
    assert (total, done, len(calls)) == (1000, 3, 3)  # guidance is one batched forward per step
    calls.clear()
    run, total, done = sampling(module, 1, 10, "ddim", 5, guidance=2.5, timed_steps=100)
    run()
    assert (total, done, len(calls)) == (5, 5, 5)


def test_quick_bench_writes_the_table_and_the_required_keys(tmp_path):
    spec = importlib.util.spec_from_file_location("bench_run", REPO / "bench" / "run.py")
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    assert bench.main(["--quick", "--compile", "--out", str(tmp_path / "result")]) == 0
    result = json.loads((tmp_path / "result.json").read_text())
    for key in ("train_step_paper_bs64_s", "sample_one_motion_default_s", "forward_paper_bs32_mfu", "text_cache_s"):
        assert result[key] > 0, key
    assert result["machine"]["cores"] >= 1 and result["quick"]
    (compiled,) = [r for r in result["rows"] if r["name"].endswith("torch.compile")]
    assert compiled["max_abs_diff"] <= 1e-5  # the compiled forward computes what eager does
    table = (tmp_path / "result.md").read_text()
    assert "| train step, tiny preset, batch 64, 20 frames |" in table and "(default sampler)" in table
    # without --official: the side-by-side table has this project's column only, with GFLOP/s and peak share
    assert result["official"] is None and all(e["official_s"] is None for e in result["comparison"])
    assert "| workload | motiondiff median | motiondiff GFLOP/s (share of matmul peak) | note |" in table
    assert "official median" not in table and "CPU flags: avx2" in table
    (train,) = [line for line in table.splitlines() if line.startswith("| train step, batch 64, 20 frames |")]
    assert re.search(r"\| \d+\.\d \(\d+%\) \|", train)


def test_forward_flops_match_the_transformer_formula():
    """Per layer 8·T·d² (QKV + output projections) + 4·B·L²·d (scores and mixing) + 4·T·d·ff (feed-forward), with
    L = frames + 1 tokens (the time/condition token), T = B·L; plus the input and output projections."""
    from motiondiff.bench.workloads import FEATURE_DIM, forward_flops
    from motiondiff.models.denoiser import PRESETS

    b, n = 1, 196
    p = PRESETS["paper"]
    d, ff, length = p["d_model"], p["ff_size"], n + 1
    tokens = b * length
    layers = p["num_layers"] * (8 * tokens * d**2 + 4 * b * length**2 * d + 4 * tokens * d * ff)
    projections = 2 * (2 * b * n * FEATURE_DIM * d)
    assert abs(forward_flops("paper", b, n) / (layers + projections) - 1) < 0.01
