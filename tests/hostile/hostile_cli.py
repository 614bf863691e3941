"""The helpers of tests/hostile (a module of its own name: `conftest` is a name every test folder has). Hostile and
careless input through the installed commands, as subprocesses (never `run(cfg)` in-process: what a
user sees is the process's stderr, exit code and the files it leaves).

`run_cli(tmp, "sample", "length=abc")` runs ``motiondiff-sample`` in ``tmp`` with outputs under ``tmp/outputs``;
`assert_refused(proc, "length")` checks exit code 2, one ``error: ...`` line naming the problem, no traceback.
"""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
BIN = Path(sys.executable).parent


def command(name: str) -> list[str]:
    """The installed console script ``motiondiff-<name>``, or ``python -m <module>`` for a dotted name."""
    if "." in name:
        return [sys.executable, "-m", name]
    script = BIN / f"motiondiff-{name}"
    if not script.exists():
        raise FileNotFoundError(f"{script} is not installed: run `make setup` (pip install -e .)")
    return [str(script)]


def cli_env(tmp: Path, env: dict | None = None) -> dict:
    """The environment a command runs in: its outputs under ``tmp/outputs`` (hydra.run.dir is not set, so the
    run-folder rules are tested too) and Hydra's short error reports."""
    return {**os.environ, "MOTIONDIFF_OUTPUT_DIR": str(tmp / "outputs"), "HYDRA_FULL_ERROR": "0", **(env or {})}


def run_cli(tmp: Path, name: str, *args: str, timeout: float = 300, env: dict | None = None,
            stdin=None) -> subprocess.CompletedProcess:  # fmt: skip
    """Run a command in ``tmp`` to its end."""
    return subprocess.run([*command(name), *args], cwd=tmp, env=cli_env(tmp, env), capture_output=True, text=True,
                          timeout=timeout, stdin=stdin)  # fmt: skip


def popen_cli(tmp: Path, name: str, *args: str, env: dict | None = None, **popen) -> subprocess.Popen:
    """Start a command in ``tmp`` and return at once (for tests that interrupt or kill it)."""
    return subprocess.Popen([*command(name), *args], cwd=tmp, env=cli_env(tmp, env), **popen)


def assert_refused(proc: subprocess.CompletedProcess, *needles: str, code: int = 2) -> str:
    """Exit ``code``, exactly one ``error: ...`` line on stderr that contains every needle (case-insensitive), and no
    traceback anywhere. Returns the line."""
    assert "Traceback" not in proc.stderr + proc.stdout, proc.stderr[-3000:]
    assert proc.returncode == code, f"exit {proc.returncode}, expected {code}\n{proc.stderr[-3000:]}"
    errors = [line for line in proc.stderr.splitlines() if line.startswith("error: ")]
    assert len(errors) == 1, f"expected one error line, got {len(errors)}:\n{proc.stderr[-3000:]}"
    for needle in needles:
        assert needle.lower() in errors[0].lower(), f"{needle!r} not in {errors[0]!r}"
    return errors[0]


def files_under(path: Path) -> list[str]:
    return sorted(str(p.relative_to(path)) for p in path.rglob("*") if p.is_file()) if path.exists() else []


@dataclass(frozen=True)
class Hostile:
    """One case: ``motiondiff-<command> *args`` in a fresh folder, refused with a line holding every needle."""

    name: str
    command: str
    args: tuple[str, ...]
    needles: tuple[str, ...]
    setup: Callable[[Path], tuple[str, ...]] | None = None  # extra arguments made from files in the case's folder
    env: dict = field(default_factory=dict)


def run_collected(request, tmp_path_factory, workers: int = 2) -> dict[str, tuple[subprocess.CompletedProcess, Path]]:
    """Run every collected ``case`` of the requesting module, ``workers`` at a time (for a module-scoped fixture:
    the subprocesses overlap, the tests then read their results). name -> (process, its folder)."""
    wanted = [item.callspec.params["case"] for item in request.session.items
              if item.module is request.module and hasattr(item, "callspec") and "case" in item.callspec.params]  # fmt: skip

    def prepared(case: Hostile) -> tuple[Hostile, Path, tuple[str, ...]]:
        tmp = tmp_path_factory.mktemp(case.name)
        return case, tmp, case.setup(tmp) if case.setup else ()

    def run(item: tuple[Hostile, Path, tuple[str, ...]]):
        case, tmp, extra = item
        return case.name, (run_cli(tmp, case.command, *case.args, *extra, env=case.env), tmp)

    # The setups run here, one after another: CPython 3.11's parser is not thread-safe (np.load parses .npy headers
    # with ast.literal_eval, and two threads at once raise "AST constructor recursion depth mismatch").
    items = [prepared(case) for case in wanted]
    with ThreadPoolExecutor(max_workers=workers) as pool:
        return dict(pool.map(run, items))
