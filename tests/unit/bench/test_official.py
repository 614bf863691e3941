"""The comparison with the official MDM code: its workloads wired to a fake checkout (tests/fixtures/
fake_official_mdm.py, written into tmp_path), `bench/run.py --quick --official` writing the side-by-side table, the
refusals of a folder that is not a checkout and of code that needs a package this machine lacks, and the table's
numbers (ratio, GFLOP/s, share of the matmul peak) and CPU flags."""

from __future__ import annotations

import importlib.util
import json
import re
import sys
from pathlib import Path
from types import ModuleType

import pytest
import torch
from fixtures.fake_official_mdm import write_fake_checkout

from motiondiff.bench import official
from motiondiff.bench.compare import comparison_markdown, comparison_table
from motiondiff.bench.official_code import load_official
from motiondiff.bench.workloads import TINY
from motiondiff.runtime.errors import UsageError
from motiondiff.runtime.hardware import cpu_flags

REPO = Path(__file__).resolve().parents[3]
OWNED = ("model", "diffusion", "utils", "data_loaders", "clip")


def bench_main():
    spec = importlib.util.spec_from_file_location("bench_run", REPO / "bench" / "run.py")
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    return bench.main


def leftovers() -> list[str]:
    return [name for name in sys.modules if name.split(".")[0] in OWNED]


def test_official_workloads_run_the_checkouts_code_and_leave_no_modules_behind(tmp_path, monkeypatch):
    sentinel = ModuleType("clip")  # an installed clip stays what it was
    monkeypatch.setitem(sys.modules, "clip", sentinel)
    code = load_official(write_fake_checkout(tmp_path))
    assert sys.modules["clip"] is sentinel and leftovers() == ["clip"]
    calls = code.MDM.__init__.__globals__["CALLS"]

    model = official.build_model(code, TINY)
    assert official.param_count(model) == sum(p.numel() for p in model.parameters()) > 0  # the stub CLIP has none
    build, built = official.build_model, []
    monkeypatch.setattr(official, "build_model", lambda *a, **k: built.append(build(*a, **k)) or built[-1])
    step = official.train_step(code, TINY, 4, 10)
    before = [p.detach().clone() for p in built[0].parameters()]
    calls[0] = 0
    assert torch.isfinite(torch.tensor(step())) and calls[0] == 1
    assert any(not torch.equal(a, b) for a, b in zip(before, built[0].parameters(), strict=True))  # AdamW stepped

    calls[0] = 0
    out = official.forward(code, TINY, 1, 10, guided=True)()
    assert out.shape == (1, 263, 1, 10) and calls[0] == 2  # ClassifierFreeSampleModel: two forwards
    run, total, done = official.sampling(code, TINY, 10, "ddpm", timed_steps=3)
    calls[0] = 0
    run()
    assert (total, done, calls[0]) == (1000, 3, 6)
    run, total, done = official.sampling(code, TINY, 10, "ddim")
    calls[0] = 0
    run()
    assert (total, done, calls[0]) == (50, 50, 100)


def test_quick_bench_with_official_writes_the_side_by_side_table(tmp_path, capsys):
    checkout = write_fake_checkout(tmp_path / "mdm")
    assert bench_main()(["--quick", "--official", str(checkout), "--out", str(tmp_path / "result")]) == 0
    result = json.loads((tmp_path / "result.json").read_text())
    assert result["official"]["path"] == str(checkout.resolve())
    fake = official.build_model(load_official(checkout), TINY)
    assert result["params"]["official"] == official.param_count(fake) and result["params"]["motiondiff"] > 0
    workloads = [e["workload"] for e in result["comparison"]]
    assert "train step, batch 64, 20 frames" in workloads and any("DDPM-1000" in w for w in workloads)
    for entry in result["comparison"]:
        assert entry["official_s"] > 0 and entry["motiondiff_s"] > 0, entry
        assert entry["official_over_motiondiff"] == pytest.approx(entry["official_s"] / entry["motiondiff_s"])
    table = (tmp_path / "result.md").read_text()
    assert "| workload | official median | motiondiff median | official ÷ motiondiff |" in table
    (train,) = [line for line in table.splitlines() if line.startswith("| train step, batch 64, 20 frames |")]
    assert len(re.findall(r"(?<=\| )\d+\.\d \(\d+%\)(?= \|)", train)) == 2  # GFLOP/s and peak share on both sides
    assert "official MDM: train step, tiny preset, batch 64, 20 frames" in table and "CPU flags: avx2" in table
    assert leftovers() == []


def test_a_folder_that_is_not_a_checkout_is_refused_in_one_line(tmp_path, capsys):
    assert bench_main()(["--quick", "--official", str(tmp_path), "--out", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "not an MDM checkout: expected model/mdm.py" in err
    with pytest.raises(UsageError, match="no such directory"):
        load_official(tmp_path / "missing")
    assert not (tmp_path / "r.json").exists()


def test_a_package_the_official_code_needs_is_named(tmp_path):
    checkout = write_fake_checkout(tmp_path, extra_import="motiondiff_test_absent_package")
    with pytest.raises(UsageError, match="needs the Python package 'motiondiff_test_absent_package'"):
        load_official(checkout)
    assert leftovers() == []
    (checkout / "utils" / "model_util.py").unlink()
    with pytest.raises(UsageError, match="expected utils/model_util.py"):
        load_official(checkout)


def test_the_table_divides_by_the_matmul_peak_of_the_rows_dtype():
    rows = [{"key": "a_s", "median_s": 2.0, "flops_per_s": 50e9}, {"key": "official_a_s", "median_s": 3.0,
            "flops_per_s": 25e9}, {"key": "b_s", "median_s": 1.0}]  # fmt: skip
    pairs = [{"workload": "train", "motiondiff_key": "a_s", "official_key": "official_a_s", "dtype": "bfloat16",
              "note": ""}, {"workload": "sample", "motiondiff_key": "b_s", "official_key": None, "dtype": None,
              "note": "50 steps"}]  # fmt: skip
    table = comparison_table(rows, {"matmul_float32_gflops": 100.0, "matmul_bfloat16_gflops": 200.0}, pairs)
    assert table[0]["motiondiff_peak_share"] == 0.25 and table[0]["official_peak_share"] == 0.125
    assert table[0]["official_over_motiondiff"] == 1.5 and table[1]["official_s"] is None
    assert comparison_markdown(table, with_official=True)[2] == (
        "| train | 3.00 s | 2.00 s | 1.50x | 25.0 (12%) | 50.0 (25%) |  |"
    )
    assert comparison_markdown(table, with_official=False)[3] == "| sample | 1.00 s | — | 50 steps |"


def test_cpu_flags_read_the_kernels_flag_list(tmp_path):
    info = tmp_path / "cpuinfo"
    info.write_text("processor\t: 0\nflags\t\t: fpu sse avx2 avx512f amx_tile\n")
    assert cpu_flags(str(info)) == {"avx2": True, "avx512f": True, "avx512_bf16": False, "amx_bf16": False,
                                    "amx_tile": True}  # fmt: skip
    assert not any(cpu_flags(str(tmp_path / "none")).values())
