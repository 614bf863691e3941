"""What every library comparison under bench/dependencies/ shares: the machine, timings, a library's install cost
and writing the JSON under docs/results/dependencies/.

The libraries compared are not the project's dependencies: install them into a scratch venv that also sees the
project's packages (bench/dependencies/README.md says how), never into the project's own venv.
"""

from __future__ import annotations

import importlib
import importlib.metadata as md
import json
import os
import platform
import re
import sys
import time
from pathlib import Path

import numpy as np
import torch
from packaging.requirements import Requirement

from motiondiff.runtime.hardware import cpu_model

REPO = Path(__file__).resolve().parents[2]
torch.set_num_threads(1)  # one thread for both sides: a fair ratio on a machine whose cores other work shares
OUT_DIR = REPO / "docs" / "results" / "dependencies"


def require(module: str, pip_name: str | None = None):
    """Import a compared library, or exit with the one line that installs it (into the scratch venv)."""
    try:
        return importlib.import_module(module)
    except ImportError:
        sys.exit(f"{module} is not installed: pip install --no-deps {pip_name or module} into the scratch venv "
                 "(bench/dependencies/README.md)")  # fmt: skip


def machine() -> dict:
    """The CPU and versions, and the load average: the 2-core machines are shared, so timings carry noise that the
    interleaved ratios of `speed` mostly cancel."""
    return {"cpu": cpu_model(), "cores": os.cpu_count(), "torch_threads": torch.get_num_threads(),
            "load_average_1min": os.getloadavg()[0], "python": platform.python_version(), "torch": torch.__version__,
            "numpy": np.__version__}  # fmt: skip


def speed(ours, theirs, repeats: int = 7, warmup: int = 1) -> dict:
    """Both on the same inputs in this run, interleaved (ours, theirs, ours, ...) so background load hits both
    alike; the fastest of `repeats` each (the least disturbed run). ratio = library / project: > 1, the project's
    code is faster."""
    for _ in range(warmup):
        ours(), theirs()
    a, b = [], []
    for _ in range(repeats):
        for fn, times in ((ours, a), (theirs, b)):
            start = time.perf_counter()
            fn()
            times.append(time.perf_counter() - start)
    return {"project_s": min(a), "library_s": min(b), "library_over_project": min(b) / min(a)}


def import_seconds(module: str) -> float:
    """Wall time of a first `import module` in a fresh interpreter that has already imported torch, numpy and scipy
    (which every motiondiff command loads): what the module adds to a command's start. Median of 3."""
    import subprocess

    code = ("import torch, numpy, scipy.spatial.transform, time; t = time.perf_counter(); "
            f"import {module}; print(time.perf_counter() - t)")  # fmt: skip
    runs = [float(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout)
            for _ in range(3)]  # fmt: skip
    return sorted(runs)[1]


def _requirements(dist: md.Distribution, extras: tuple[str, ...] = ()) -> list[str]:
    """Normalised names of what `dist` requires on this interpreter (markers evaluated; ``extras`` switched on)."""
    names = []
    for text in dist.requires or []:
        req = Requirement(text)
        if req.marker is None or any(req.marker.evaluate({"extra": e}) for e in ("", *extras)):
            names.append(_norm(req.name))
    return names


def _norm(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def _installed_bytes(dist: md.Distribution) -> int:
    """Bytes its RECORD lists (what the wheel installs, without the .pyc files pip compiles afterwards)."""
    return sum(int(f.size or 0) for f in dist.files or [] if f.size)


def _closure(names, extras: tuple[str, ...] = ()) -> tuple[dict[str, int], list[str]]:
    """Every installed package `names` pull in, recursively, with its size; and the required ones not installed."""
    sizes, missing, todo = {}, [], list(names)
    while todo:
        name = _norm(todo.pop())
        if name in sizes or name in missing:
            continue
        try:
            dist = md.distribution(name)
        except md.PackageNotFoundError:
            missing.append(name)
            continue
        sizes[name] = _installed_bytes(dist)
        todo.extend(_requirements(dist))
    return sizes, missing


def install_cost(name: str, extras: tuple[str, ...] = ()) -> dict:
    """The library's own installed size, every package it pulls in (recursively) that motiondiff's own runtime
    dependencies do not (the dev extra's test-only packages count as added), with their sizes, and its torch pin."""
    root = md.distribution(name)
    project, project_missing = _closure(_requirements(md.distribution("motiondiff")))
    pulled, missing = _closure(_requirements(root, extras))
    missing = [m for m in missing if m not in project_missing]  # a core dependency's own gap is not this library's
    added = {k: v for k, v in pulled.items() if k not in project}
    torch_req = [str(Requirement(r).specifier) or "any" for r in root.requires or []
                 if _norm(Requirement(r).name) == "torch" and (Requirement(r).marker is None
                 or any(Requirement(r).marker.evaluate({"extra": e}) for e in ("", *extras)))]  # fmt: skip
    licence = root.metadata.get("License-Expression") or root.metadata.get("License") or ""
    classifiers = [c.split(" :: ")[-1] for c in root.metadata.get_all("Classifier") or [] if "License" in c]
    return {
        "version": root.version,
        "installed_bytes": _installed_bytes(root),
        "requires": _requirements(root, extras),
        "added_packages": added,
        "added_bytes": sum(added.values()),
        "already_core_dependencies": sorted(set(pulled) - set(added)),
        "required_but_not_installed": sorted(missing),
        "torch_requirement": torch_req,
        "licence_metadata": (licence.splitlines()[0][:80] if licence else "") or "; ".join(classifiers) or "none",
    }


def max_abs(a, b) -> float:
    a = a.detach().cpu().numpy() if isinstance(a, torch.Tensor) else np.asarray(a)
    b = b.detach().cpu().numpy() if isinstance(b, torch.Tensor) else np.asarray(b)
    return float(np.max(np.abs(a.astype(np.float64) - b.astype(np.float64)))) if a.size else 0.0


def write(name: str, result: dict) -> Path:
    """docs/results/dependencies/<name>.json, with the machine and the date; prints where it went."""
    OUT_DIR.mkdir(parents=True, exist_ok=True)
    path = OUT_DIR / f"{name}.json"
    payload = {"machine": machine(), "date": time.strftime("%Y-%m-%d"), **result}
    path.write_text(json.dumps(payload, indent=2, default=float) + "\n")
    print(f"wrote {path.relative_to(REPO)}")
    return path
