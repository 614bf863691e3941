"""The whole benchmark in one process: `make bench` (bench/run.py) calls `run_suite`.

Rows (medians over repeats after a warm-up; peak resident memory of each piece of work):
- a plain fp32 matmul (4096x2048x2048) and, where the CPU has native bf16, the same in bf16: the machine's GEMM speed;
- training steps at the paper preset (batch 64 and 16) and the CPU preset (batch 64), 196 frames, trans_enc;
- the denoiser forward at batch 1 and 32 (paper preset), with its counted FLOP/s against a matmul of its
  feed-forward shape in the same run (model FLOPs utilisation);
- sampling one motion and 32 motions from text with DDPM-1000, DDIM-50 and DDIM-10, with and without guidance, and
  with sample.py's default sampler; chains longer than ``timed_steps`` are timed over their first steps and scaled
  (each step runs the same forward), which the row says;
- text encoding of one prompt with the encoder and from the embedding cache;
- the side-by-side comparison (``compare``): the same workloads on the official MDM code when ``official`` names a
  local checkout of it, and this project's column alone otherwise.
``quick=True`` shrinks everything (tiny network, 20 frames, 1 repeat) so the tests can run the whole suite.
"""

from __future__ import annotations

import datetime
import time
from collections.abc import Callable

import torch

from motiondiff.bench import workloads
from motiondiff.bench.compare import comparison_table, params_and_notes, run_comparison
from motiondiff.bench.flops import count_flops, matmul_flops_per_s
from motiondiff.bench.official_code import load_official
from motiondiff.bench.report import machine
from motiondiff.bench.timing import PeakMemory, median_seconds
from motiondiff.bench.workloads import TINY
from motiondiff.lit.conditions import text_encoder_kwargs
from motiondiff.model_files.loading import load_model as load_module
from motiondiff.model_files.resolve import find_model
from motiondiff.models.denoiser import PRESETS
from motiondiff.runtime.paths import REPO_DIR


def default_sampler() -> tuple[str, int | None]:
    """sample.py's default sampler and steps (conf/sample.yaml's defaults)."""
    from hydra import compose, initialize_config_dir

    with initialize_config_dir(str(REPO_DIR / "conf"), version_base="1.3"):
        cfg = compose("sample")
    return str(cfg.sampler.name), cfg.sampler.steps


class Suite:
    def __init__(self, quick: bool):
        self.quick = quick
        self.rows: list[dict] = []
        self.keys: dict[str, float] = {}
        self.repeats, self.warmup = (1, 0) if quick else (3, 1)

    def time(self, name: str, fn: Callable[[], object], key: str | None = None, scale: float = 1.0,
             repeats: int | None = None, **detail) -> dict:  # fmt: skip
        with PeakMemory() as mem:
            timing = median_seconds(fn, repeats or self.repeats, self.warmup)
        row = {"name": name, "median_s": timing["median_s"] * scale, "times_s": [t * scale for t in timing["times_s"]],
               "peak_rss_mb": mem.peak_bytes / 2**20, "key": key, **detail}  # fmt: skip
        row["detail"] = "; ".join(
            [*(str(v) for k, v in detail.items() if k == "note"), f"peak RSS {row['peak_rss_mb']:.0f} MB"]
        )
        self.rows.append(row)
        if key:
            self.keys[key] = row["median_s"]
        print(f"{name}: {row['median_s']:.4f} s", flush=True)
        return row


def compile_rows(s: Suite, quick: bool) -> None:
    """torch.compile against eager for one guided sampling step of the CPU preset (batch 2): compile time, step time
    and the largest difference of the outputs."""
    preset, frames = (TINY, 20) if quick else ("cpu", 196)
    eager = workloads.forward(preset, 2, frames)
    compiled = workloads.forward(preset, 2, frames, compile=True)
    start = time.perf_counter()
    out = compiled()
    seconds = time.perf_counter() - start
    diff = float((out - eager()).abs().max())
    s.time("denoiser forward, cpu preset, batch 2, eager", eager, key="forward_cpu_bs2_eager_s")
    row = s.time("denoiser forward, cpu preset, batch 2, torch.compile", compiled, key="forward_cpu_bs2_compiled_s",
                 note=f"compiled in {seconds:.0f} s; largest difference from eager {diff:.1e}")  # fmt: skip
    row.update(compile_s=seconds, max_abs_diff=diff)


def run_suite(quick: bool = False, model: str = "shipped", command: str = "", compile: bool = False,
              official: str | None = None) -> dict:  # fmt: skip
    """Every row; ``official``: a local checkout of the official MDM code to compare with (checked and imported
    before anything is timed, so a bad path fails at once)."""

    start = time.perf_counter()
    code = load_official(official) if official else None
    s = Suite(quick)
    bf16_options = [False, True] if machine()["native_bf16"] else [False]
    frames = 20 if quick else 196
    paper = TINY if quick else "paper"
    notes = []

    # The machine's GEMM.
    gemm = (256, 128, 128) if quick else (4096, 2048, 2048)
    for bf16 in bf16_options:
        dtype = torch.bfloat16 if bf16 else torch.float32
        ref = matmul_flops_per_s(*gemm, dtype=dtype, repeats=s.repeats)
        s.rows.append({"name": f"matmul {gemm[0]}x{gemm[1]}x{gemm[2]} {ref['dtype']}", "median_s": ref["median_s"],
                       "flops_per_s": ref["flops_per_s"], "detail": f"{ref['flops_per_s'] / 1e9:.1f} GFLOP/s"})  # fmt: skip
        s.keys[f"matmul_{ref['dtype']}_gflops"] = ref["flops_per_s"] / 1e9

    # Training steps.
    for preset, batch, key in ((paper, 64, "train_step_paper_bs64"), (paper, 16, "train_step_paper_bs16"),
                               (TINY if quick else "cpu", 64, "train_step_cpu_bs64")):  # fmt: skip
        for bf16 in bf16_options:
            step = workloads.train_step(preset, 4 if quick else batch, frames, bf16=bf16)
            flops = count_flops(step)
            suffix = "_bf16" if bf16 else ""
            label = f"train step, {'tiny' if quick else key.split('_')[2]} preset, batch {batch}, {frames} frames{', bf16 autocast' if bf16 else ''}"
            row = s.time(label, step, key=f"{key}{suffix}_s", note=f"{flops / 1e9:.1f} GFLOP")
            row["flops_per_s"] = flops / row["median_s"]
            row["detail"] += f"; {row['flops_per_s'] / 1e9:.1f} GFLOP/s"

    # Denoiser forward and its FLOPs utilisation.
    arch = PRESETS["paper"] if not quick else TINY
    for batch in (1, 32):
        for bf16 in bf16_options:
            run = workloads.forward(paper, batch, frames, bf16=bf16)
            flops = workloads.forward_flops(paper, batch, frames)
            suffix = "_bf16" if bf16 else ""
            row = s.time(f"denoiser forward, {'tiny' if quick else 'paper'} preset, batch {batch}{' bf16' if bf16 else ''}", run,
                         key=f"forward_paper_bs{batch}{suffix}_s")  # fmt: skip
            row["flops_per_s"] = flops / row["median_s"]
            shape = (batch * (frames + 1), arch["d_model"], arch["ff_size"])  # the feed-forward GEMM
            ref = matmul_flops_per_s(*shape, dtype=torch.bfloat16 if bf16 else torch.float32, repeats=max(3, s.repeats))
            row["mfu_vs_matmul"] = row["flops_per_s"] / ref["flops_per_s"]
            row["detail"] += (f"; {row['flops_per_s'] / 1e9:.1f} GFLOP/s = {row['mfu_vs_matmul']:.0%} of a "
                              f"{shape[0]}x{shape[1]}x{shape[2]} matmul ({ref['flops_per_s'] / 1e9:.1f} GFLOP/s)")  # fmt: skip
            s.keys[f"forward_paper_bs{batch}{suffix}_mfu"] = row["mfu_vs_matmul"]

    pairs = run_comparison(s, quick, code, bf16_options)
    if compile:
        compile_rows(s, quick)

    # Sampling from text with the real model.
    module = load_module(find_model(model, REPO_DIR / "outputs"))
    guidance = module.default_guidance
    name, steps = default_sampler()
    name = module.resolve_sampler(name)  # sampler=auto: the model's own
    steps = module.default_steps(name) if steps is None else steps
    chains = [("ddpm", None), ("ddim", 50), ("ddim", 10)]
    if (name, steps) not in chains:
        chains.append((name, steps))
    for count in (1, 32):
        timed = 2 if quick else (100 if count == 1 else 10)
        for sampler, n in chains:
            is_default = (sampler, n) == (name, steps)
            for g in (guidance, 1.0):
                run, total, done = workloads.sampling(module, 2 if quick and count > 1 else count, frames, sampler,
                                                      n, g, timed_steps=timed)  # fmt: skip
                label = (
                    f"sample {count} motion{'s' if count > 1 else ''}, {sampler.upper()}-{total}"
                    f"{' (default sampler)' if is_default else ''}, {'guidance ' + str(g) if g != 1 else 'no guidance'}"
                )
                note = f"timed over {done} of {total} steps, scaled" if done < total else f"{total} steps"
                guided = "guided" if g != 1 else "unguided"
                row = s.time(
                    label, run, key=f"sample_{count}_{sampler}{total}_{guided}_s", scale=total / done, note=note
                )
                if is_default and count == 1 and g != 1:
                    s.keys["sample_one_motion_default_s"] = row["median_s"]
    # Text encoding.
    encode, lookup = workloads.text_encoding(text_encoder_kwargs(module.hparams.text_encoder))
    s.time("encode one prompt with the text encoder", encode, key="text_encode_s", repeats=max(5, s.repeats))
    s.time("one prompt from the text-embedding cache", lookup, key="text_cache_s", repeats=max(5, s.repeats))

    notes.append(f"Sampling uses `{model}` ({module.hparams.model.get('name', '?')} preset, "
                 f"{module.hparams.feature_dim} features) at {frames} frames; guidance {guidance} is its default.")  # fmt: skip
    notes.append("Training and forward rows use random features (263 wide) and random 384-d caption features: "
                 "train.py looks captions up in a pre-computed table, so no text encoder runs in a step.")  # fmt: skip
    params, comparison_notes = params_and_notes(code, quick)
    notes += comparison_notes
    if not machine()["native_bf16"]:
        notes.append("No bf16 rows: this CPU has no native bf16 (oneDNN would emulate it, 10-20x slower).")
    return {"machine": machine(), "date": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
            "command": command, "quick": quick, "wall_s": time.perf_counter() - start, **s.keys,
            "rows": s.rows, "comparison": comparison_table(s.rows, s.keys, pairs), "params": params,
            "official": {"path": str(code.path), "commit": code.commit} if code else None, "notes": notes}  # fmt: skip
