"""What this machine's CPU does fast. bf16 autocast is 1.4-2.7x faster than float32 where the CPU has bf16
instructions (AVX512-BF16, AMX), and ~10-20x SLOWER where it has not (measured on an AVX2-only AMD EPYC: 0.2 vs
2.1 training steps/s), because oneDNN then emulates every bf16 op. So the CPU presets ask here instead of assuming."""

from __future__ import annotations

import functools
import platform

import torch

from motiondiff.runtime.errors import UsageError


@functools.cache
def cpu_has_fast_bf16() -> bool:
    """True when the CPU has native bf16 instructions (AVX512-BF16 or AMX) and oneDNN has bf16 kernels for it.
    oneDNN calls bf16 "supported" on every AVX512 CPU, where it converts to float32 around each op: on a Xeon with
    AVX512F but no AVX512-BF16 its bf16 matmuls measured 2.5-4x slower than float32. So the kernel's CPU flags decide
    where they can be read, and torch's probe alone only where they cannot (another OS)."""
    flags = cpu_flags()
    if any(flags.values()) and not (flags["avx512_bf16"] or flags["amx_bf16"]):
        return False
    try:
        return bool(torch.ops.mkldnn._is_mkldnn_bf16_supported())
    except (AttributeError, RuntimeError):  # a torch without the probe: judge by the instruction set
        return torch.backends.cpu.get_cpu_capability() in ("AVX512", "AMX")


def fast_cpu_precision() -> str:
    """Lightning precision for CPU presets: 'bf16-mixed' where native, else '32-true'."""
    return "bf16-mixed" if cpu_has_fast_bf16() else "32-true"


@functools.cache
def bf16_matmul_is_faster(rows: int, inner: int, cols: int) -> bool:
    """Whether a (rows x inner) @ (inner x cols) product, the weight cast to bf16 as autocast does it on every call,
    runs faster in bf16 than in float32 on this CPU (medians of 7 after a warm-up; about 0.1 s once per shape).
    Native bf16 is not always a gain: on an AVX512-BF16 CPU without AMX a small model sampled 5x slower in bf16.
    The two are timed in turn, so that a burst of load (another process starting) slows both alike rather than one
    block of them (docs/results/evaluation_speed)."""
    if not cpu_has_fast_bf16():
        return False
    import time

    x, w = torch.randn(rows, inner), torch.randn(inner, cols)
    candidates = {"fp32": lambda: x @ w, "bf16": lambda: x.to(torch.bfloat16) @ w.to(torch.bfloat16)}
    times: dict[str, list[float]] = {name: [] for name in candidates}
    with torch.inference_mode():
        for fn in candidates.values():  # warm-up
            fn()
        for _ in range(7):
            for name, fn in candidates.items():
                start = time.perf_counter()
                fn()
                times[name].append(time.perf_counter() - start)
    fp32, bf16 = (sorted(times[name])[3] for name in candidates)
    return bf16 < 0.9 * fp32


PRECISIONS = {"32-true": "32-true", "32": "32-true", "fp32": "32-true", "bf16-mixed": "bf16-mixed",
              "bf16": "bf16-mixed"}  # fmt: skip


def inference_precision(name: str, device: str = "cpu", shape: tuple[int, int, int] | None = None) -> str:
    """``precision=`` for sampling: "auto" is bf16 autocast where the device runs it natively and, on a CPU, where
    a matmul of the model's feed-forward `shape` (rows, d_model, ff_size) measured faster in bf16
    (`bf16_matmul_is_faster`); full precision elsewhere. "bf16"/"32" force one."""

    key = str(name).strip().lower()
    if key == "auto":
        if str(device).startswith("cuda"):
            return "bf16-mixed" if torch.cuda.is_available() and torch.cuda.is_bf16_supported() else "32-true"
        if str(device) != "cpu" or not cpu_has_fast_bf16():
            return "32-true"
        return "bf16-mixed" if shape is None or bf16_matmul_is_faster(*shape) else "32-true"
    if key not in PRECISIONS:
        raise UsageError(f"precision={name!r}: choose auto (bf16 where the hardware has it), bf16 or 32")
    return PRECISIONS[key]


def cpu_model() -> str:
    """The CPU's model name (/proc/cpuinfo), for benchmark records and model cards."""
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


SPEED_FLAGS = ("avx2", "avx512f", "avx512_bf16", "amx_bf16", "amx_tile")


def cpu_flags(cpuinfo: str = "/proc/cpuinfo") -> dict[str, bool]:
    """Which of the instruction sets that decide CPU matmul speed the kernel reports (all False where ``cpuinfo``
    cannot be read). torch may still not use one it lacks kernels for: see ``cpu_has_fast_bf16``."""
    try:
        with open(cpuinfo) as f:
            flags = next((line.split(":", 1)[1].split() for line in f if line.startswith("flags")), [])
    except OSError:
        flags = []
    return {name: name in flags for name in SPEED_FLAGS}


def resolve_device(name: str) -> str:
    """The torch device of ``device=``: ``auto`` is CUDA where a GPU is visible, else the CPU; an explicit device
    that this machine lacks is one clear error instead of torch's traceback deep inside loading."""
    import torch

    name = str(name).strip().lower()
    if name == "auto":
        return "cuda" if torch.cuda.is_available() else "cpu"
    if name.startswith("cuda") and not torch.cuda.is_available():
        raise UsageError(f"device={name} but this machine has no CUDA device torch can use; use device=auto or cpu")
    if name.startswith("mps") and not torch.backends.mps.is_available():
        raise UsageError(f"device={name} but MPS is not available here; use device=auto or cpu")
    try:
        kind = torch.device(name).type
    except RuntimeError:
        kind = None
    if kind not in ("cpu", "cuda", "mps"):  # meta, xla, ...: torch names them, but no motion can be sampled there
        raise UsageError(f"unknown device={name!r}; use auto, cpu, cuda or cuda:<index>")
    return name
