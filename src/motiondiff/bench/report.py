"""Where a benchmark ran (the numbers mean nothing without it: CPU, the instruction sets that decide its matmul
speed, threads, allocator) and its Markdown tables."""

from __future__ import annotations

import os
import platform

import torch

from motiondiff.bench.compare import comparison_markdown
from motiondiff.bench.timing import format_seconds
from motiondiff.runtime.hardware import cpu_flags, cpu_has_fast_bf16, cpu_model


def allocator() -> str:
    """The C allocator the process runs with: an LD_PRELOADed one (``make`` preloads tcmalloc where it is
    installed) or glibc's."""
    preload = os.environ.get("LD_PRELOAD", "")
    for name in ("tcmalloc", "jemalloc"):
        if name in preload:
            return name
    return "glibc malloc"


def machine() -> dict:
    return {"cpu": cpu_model(), "cores": os.cpu_count(), "torch_threads": torch.get_num_threads(),
            "torch": torch.__version__, "cpu_capability": torch.backends.cpu.get_cpu_capability(),
            "native_bf16": cpu_has_fast_bf16(), "cpu_flags": cpu_flags(), "allocator": allocator(), "python": platform.python_version(),
            "platform": platform.platform()}  # fmt: skip


def flags_line(flags: dict[str, bool]) -> str:
    return "CPU flags: " + ", ".join(f"{name} {'yes' if on else 'no'}" for name, on in flags.items()) + "."


def markdown(result: dict) -> str:

    m = result["machine"]
    lines = [
        "# motiondiff benchmark",
        "",
        f"{m['cpu']}, {m['cores']} cores, {m['torch_threads']} torch threads, torch {m['torch']} "
        f"({m['cpu_capability']}; native bf16: {m['native_bf16']}; allocator: {m.get('allocator', 'glibc malloc')}). "
        f"`{result['command']}`, {result['date']}, "
        f"{result['wall_s']:.0f} s in all. Medians over repeats after a warm-up.",
        "",
        flags_line(m.get("cpu_flags", {})),
        "",
        "| what | median | detail |",
        "|---|---:|---|",
    ]
    for row in result["rows"]:
        lines.append(f"| {row['name']} | {format_seconds(row['median_s'])} | {row.get('detail', '')} |")
    if result.get("comparison"):
        side = "the official MDM code and motiondiff" if result.get("official") else "motiondiff"
        size = "tiny" if result.get("quick") else "paper"
        lines += ["", f"## Side by side: {side}, {size} preset, same workloads, same run", ""]
        lines += comparison_markdown(result["comparison"], with_official=bool(result.get("official")))
    lines += ["", *[f"- {note}" for note in result.get("notes", [])], ""]
    return "\n".join(lines)
