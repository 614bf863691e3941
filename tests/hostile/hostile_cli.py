"""The helpers of tests/hostile (a module of its own name: `conftest` is a name every test folder has). Hostile and
careless input through the installed commands' whole entry path (argument checks, Hydra, the error boundary, the
exit code): what a user sees is the stderr, the exit code and the files left. One case of each kind of failure runs
as a real subprocess (``Hostile(process=True)``); the others run the same console-script function in this process
(`run_in_process`: same argv, environment, folder and captured output), which spares ~9 s of imports per case.

`run_cli(tmp, "sample", "length=abc")` runs ``motiondiff-sample`` in ``tmp`` with outputs under ``tmp/outputs``;
`assert_refused(proc, "length")` checks exit code 2, one ``error: ...`` line naming the problem, no traceback.
"""

from __future__ import annotations

import functools
import os
import runpy
import subprocess
import sys
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from importlib.metadata import entry_points
from pathlib import Path

from fixtures.in_process import call_main

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


def run_in_process(tmp: Path, name: str, *args: str, env: dict | None = None) -> subprocess.CompletedProcess:
    """``motiondiff-<name> *args`` (or ``python -m <name>`` for a dotted name) called in this process as its console
    script would be, in ``tmp`` with the environment of `cli_env` (see fixtures.in_process.call_main)."""
    if "." in name:
        main = functools.partial(runpy.run_module, name, run_name="__main__", alter_sys=True)
    else:
        (script,) = entry_points(group="console_scripts", name=f"motiondiff-{name}")
        main = script.load()
    return call_main(main, [f"motiondiff-{name}", *args], tmp, cli_env(tmp, env))


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
    """One case: ``motiondiff-<command> *args`` in a fresh folder, refused with a line holding every needle; in a
    subprocess when ``process`` (one case per kind of failure), else in this process (`run_in_process`)."""

    name: str
    command: str
    args: tuple[str, ...]
    needles: tuple[str, ...]
    setup: Callable[[Path], tuple[str, ...]] | None = None  # extra arguments made from files in the case's folder
    env: dict = field(default_factory=dict)
    process: bool = False


def run_collected(request, tmp_path_factory, workers: int = 2) -> dict[str, tuple[subprocess.CompletedProcess, Path]]:
    """Run every collected ``case`` of the requesting module (for a module-scoped fixture; the tests then read the
    results): the subprocess cases ``workers`` at a time in threads, while the in-process cases run one after
    another in this thread. name -> (completed process, its folder)."""
    wanted = [item.callspec.params["case"] for item in request.session.items
              if item.module is request.module and hasattr(item, "callspec") and "case" in item.callspec.params]  # fmt: skip

    def prepared(case: Hostile) -> tuple[Hostile, Path, tuple[str, ...]]:
        tmp = tmp_path_factory.mktemp(case.name)
        return case, tmp, case.setup(tmp) if case.setup else ()

    def run(item: tuple[Hostile, Path, tuple[str, ...]]):
        case, tmp, extra = item
        runner = run_cli if case.process else run_in_process
        return case.name, (runner(tmp, case.command, *case.args, *extra, env=case.env), tmp)

    # The setups run here, one after another: CPython 3.11's parser is not thread-safe (np.load parses .npy headers
    # with ast.literal_eval, and two threads at once raise "AST constructor recursion depth mismatch").
    items = [prepared(case) for case in wanted]
    with ThreadPoolExecutor(max_workers=workers) as pool:
        started = [pool.submit(run, item) for item in items if item[0].process]
        done = [run(item) for item in items if not item[0].process]
        return dict(done + [f.result() for f in started])
