"""Where a training and an evaluation CPU minute goes (issue 39), as ratios measured in one run.

    python bench/cpu_minutes.py [--out bench/results/cpu_minutes.md] [--rounds 3]

1. The training step of the small model (`model=cpu`, d 128, 4 layers) and of d 256 at batch 64 x 120 frames (the
   full-Bandai recipe's longest window), fp32 and bf16 autocast, with dropout 0.1 and 0: the median step, its
   GFLOP/s and its share of a large bf16 (fp32) matmul's rate measured in the same run.
2. Evaluation sampling: the shipped text model generating one batch of 128 motions of 120 frames with guidance, DDIM-50
   against DPM-Solver++ 10 steps, alternated `--rounds` times; the ratio, and what 20 replications of a 277-clip
   split cost (11,080 motions: label and random captions) at each rate.
Rows are measured alternately in one process, so load from other work shifts them together; the CPU is named.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import torch

from motiondiff.bench import workloads as W
from motiondiff.bench.timing import median_seconds
from motiondiff.runtime.hardware import cpu_has_fast_bf16, cpu_model

BATCH, FRAMES = 64, 120
SPLIT_MOTIONS = 277 * 2 * 20  # the test split, label and random captions, 20 replications


def _median_time(fn, repeats: int, warmup: int = 3) -> float:
    return median_seconds(fn, repeats, warmup)["median_s"]


def matmul_peak(dtype: torch.dtype) -> float:
    """GFLOP/s of a 4096 x 2048 x 2048 matmul in `dtype`."""
    a, b = torch.randn(4096, 2048, dtype=dtype), torch.randn(2048, 2048, dtype=dtype)
    return 2 * 4096 * 2048 * 2048 / _median_time(lambda: a @ b, 5, 2) / 1e9


def train_rows(repeats: int) -> list[tuple[str, float, float, float]]:
    """(label, step seconds, GFLOP/s, share of the matmul peak of its precision)."""
    peaks = {False: matmul_peak(torch.float32)}
    if cpu_has_fast_bf16():
        peaks[True] = matmul_peak(torch.bfloat16)
    wide = dict(W.PRESETS["cpu"], d_model=256, ff_size=512)
    rows = []
    for name, preset in (("d 128, 4 layers (model=cpu)", W.PRESETS["cpu"]), ("d 256, 4 layers", wide)):
        for dropout in (0.1, 0.0):
            for bf16 in (False, True) if cpu_has_fast_bf16() else (False,):  # emulated bf16 (AVX2) takes hours
                net = dict(preset, dropout=dropout)
                step = W.batch_step(net, bf16)
                data = W.random_batch(BATCH, FRAMES)
                seconds = _median_time(lambda: step(data["x0"], data["mask"], data["cond"]), repeats)  # noqa: B023
                rate = 3 * W.forward_flops(net, BATCH, FRAMES) / seconds / 1e9
                label = f"{name}, dropout {dropout:g}, {'bf16 autocast' if bf16 else 'fp32'}"
                rows.append((label, seconds, rate, rate / peaks[bf16]))
    return rows


def sampling_rows(rounds: int) -> tuple[dict[str, list[float]], str]:
    """Seconds per 128 guided motions of 120 frames with the shipped text model, per sampler, alternated; and the
    precision evaluate.py would sample in."""
    from motiondiff.lit.generation import feed_forward_shape, generate_features
    from motiondiff.model_files.loading import load_model
    from motiondiff.model_files.resolve import SHIPPED_MODELS
    from motiondiff.runtime.hardware import inference_precision

    module = load_model(SHIPPED_MODELS["text"])
    prompts = [f"a person walks forward {i}" for i in range(128)]
    frames = torch.full((128,), FRAMES)
    precision = inference_precision("auto", "cpu", feed_forward_shape(module, 128, FRAMES))  # what evaluate.py picks
    samplers = {"DDIM-50": ("ddim", 50), "DPM-Solver++ 10": ("dpmpp", 10)}
    times: dict[str, list[float]] = {k: [] for k in samplers}
    for _ in range(rounds):
        for label, (sampler, steps) in samplers.items():
            generator = torch.Generator().manual_seed(0)
            start = time.perf_counter()
            generate_features(module, prompts, frames, batch_size=128, generator=generator, sampler=sampler,
                              steps=steps, guidance=module.default_guidance, precision=precision)  # fmt: skip
            times[label].append(time.perf_counter() - start)
    return times, precision


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "results" / "cpu_minutes.md")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--repeats", type=int, default=8)
    args = parser.parse_args()
    torch.manual_seed(0)
    lines = ["# Where a CPU minute goes (issue 39)", "",
             f"{torch.get_num_threads()} threads on a {cpu_model()} (native bf16: {cpu_has_fast_bf16()}), torch "
             f"{torch.__version__}, {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}. `python bench/cpu_minutes.py`.",
             "", f"## Training step, batch {BATCH} x {FRAMES} frames", "",
             "| network | step | GFLOP/s | share of the matmul peak |", "|---|---:|---:|---:|"]  # fmt: skip
    for label, seconds, rate, share in train_rows(args.repeats):
        lines.append(f"| {label} | {seconds * 1000:.0f} ms | {rate:.1f} | {share:.0%} |")
    times, precision = sampling_rows(args.rounds)
    base = statistics.median(times["DDIM-50"])
    lines += ["", f"## Evaluation sampling: 128 guided motions of 120 frames, shipped text model, {precision}", "",
              "| sampler | median s per 128 motions | ratio to DDIM-50 | 20 replications of 277 clips (11,080 motions) |",
              "|---|---:|---:|---:|"]  # fmt: skip
    for label, values in times.items():
        med = statistics.median(values)
        lines.append(f"| {label} | {med:.2f} | {base / med:.2f}x | {med * SPLIT_MOTIONS / 128 / 60:.1f} min |")
    text = "\n".join(lines) + "\n"
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text)
    print(text)


if __name__ == "__main__":
    main()
