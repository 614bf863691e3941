"""Interrupted and overlapping runs through the installed commands: Ctrl-C during sampling is one line, exit 130 and
no folder left; a second run aimed at a folder another live run is writing is refused and changes nothing there."""

from __future__ import annotations

import os
import signal
import subprocess
import time

import pytest
from hostile_cli import assert_refused, files_under, popen_cli, run_in_process
from kill_runs import BANDAI, PREPARE

from motiondiff.runtime.boundary import Stopped, guarded, signal_behind, stop_on_sigterm

PROMPTS = "".join(f"a person walks forward then turns {k} times\n" for k in range(20))


def start(tmp, name, *args):
    return popen_cli(tmp, name, *args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _as_at_a_terminal() -> None:
    """Ctrl-C's default action in the command, as at a terminal: a suite started in the background (``make test &``,
    nohup) ignores SIGINT, its children inherit that, and Python then installs no KeyboardInterrupt handler."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def wait_for(predicate, timeout=120.0):
    deadline = time.time() + timeout
    while time.time() < deadline:
        if predicate():
            return True
        time.sleep(0.1)
    return False


def interrupt_while_writing(tmp_path, signum: int, code: int, needle: str, **popen) -> None:
    """Send ``signum`` once the first sample's files are written, while the other nineteen are still being written
    (their videos take seconds each, so the moment is certain however loaded the machine is): exit ``code``, one
    line holding ``needle``, and nothing half-written, no folder and no lock left."""
    (tmp_path / "prompts.txt").write_text(PROMPTS)
    stderr = tmp_path / "stderr.txt"
    with stderr.open("w") as err_file:
        proc = popen_cli(tmp_path, "sample", "checkpoint=shipped", "prompts_file=prompts.txt", "length=1",
                         "export=[bvh,mp4]", env={"PYTHONUNBUFFERED": "1"}, stdout=subprocess.PIPE, stderr=err_file,
                         text=True, **popen)  # fmt: skip
        try:
            written = wait_for(lambda: any(p.suffix == ".bvh" for p in (tmp_path / "outputs").rglob("*")), 600)
            assert written and proc.poll() is None, "no sample was written, or the run ended before the signal"
            proc.send_signal(signum)
            out, _ = proc.communicate(timeout=120)
        finally:
            proc.kill()
    completed = subprocess.CompletedProcess(proc.args, proc.returncode, out, stderr.read_text())
    assert_refused(completed, needle, code=code)
    assert files_under(tmp_path / "outputs") == [], "the stopped run left its partial samples or its lock"


def test_ctrl_c_while_writing_is_one_line_exit_130_and_leaves_no_folder(tmp_path):
    interrupt_while_writing(tmp_path, signal.SIGINT, 130, "interrupted", preexec_fn=_as_at_a_terminal)


def test_a_second_run_into_a_folder_in_use_is_refused_and_changes_nothing(tmp_path):
    run_dir = tmp_path / "shared-run"
    tiny = ("model.d_model=32", "model.num_layers=1", "model.num_heads=2", "model.ff_size=64", "logger=csv",
            "condition=none", "trainer.max_steps=100000", "checkpoint_every=100000")  # fmt: skip
    first = start(tmp_path, "train", *tiny, f"hydra.run.dir={run_dir}")
    try:
        assert wait_for(lambda: (run_dir / "csv").exists()), "the first training did not start"
        before = files_under(run_dir)
        records = {p.name: p.read_bytes() for p in (run_dir / ".hydra").iterdir()}  # the first run's config
        second = run_in_process(tmp_path, "sample", "checkpoint=shipped", "text=walk", "length=1", "export=none",
                                f"hydra.run.dir={run_dir}")  # fmt: skip
        assert_refused(second, "another run", str(run_dir))
        assert not any(name.startswith("sample") or name.endswith(".npy") for name in files_under(run_dir))
        assert set(before) <= set(files_under(run_dir))
        assert {p.name: p.read_bytes() for p in (run_dir / ".hydra").iterdir()} == records, "records rewritten"
    finally:
        first.kill()
        first.wait()


def test_sigterm_while_writing_is_one_line_exit_143_and_leaves_no_folder(tmp_path):
    """`kill <pid>` (a scheduler's time limit) at the same moment as the Ctrl-C above (Python's default would end
    at once and leave the run's lock)."""
    interrupt_while_writing(tmp_path, signal.SIGTERM, 143, "stopped by SIGTERM")


def test_sigterm_during_training_exits_143_and_keeps_the_checkpoints(tmp_path):
    run_dir = tmp_path / "run"
    tiny = ("model.d_model=32", "model.num_layers=1", "model.num_heads=2", "model.ff_size=64", "logger=csv",
            "condition=none", "trainer.max_steps=100000", "checkpoint_every=5")  # fmt: skip
    proc = start(tmp_path, "train", *tiny, f"hydra.run.dir={run_dir}")
    try:
        assert wait_for(lambda: any((run_dir / "checkpoints").glob("step*.ckpt")), 600), "no checkpoint was written"
        proc.send_signal(signal.SIGTERM)
        out, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
    assert proc.returncode == 143, f"exit {proc.returncode}: {err[-500:]}"
    assert "Traceback" not in err
    (line,) = [line for line in err.splitlines() if line.startswith("error: ")]
    steps = sorted((int(p.stem[4:]), p) for p in (run_dir / "checkpoints").glob("step*.ckpt"))
    last = run_dir / "checkpoints" / "last.ckpt"
    copied = last.is_file() and last.stat().st_mtime >= steps[-1][1].stat().st_mtime
    resume = last if copied else steps[-1][1]  # a stop between step*.ckpt and its last.ckpt copy
    assert line == (f"error: stopped by SIGTERM; its last checkpoint (step {steps[-1][0]}) is kept: resume with "
                    f"ckpt_path={resume}"), line  # fmt: skip
    assert any((run_dir / "checkpoints").glob("*.ckpt")) and not (run_dir / ".motiondiff.lock").exists()


@pytest.mark.skipif(not BANDAI.is_file(), reason=f"needs the Bandai Namco data at {BANDAI}")
@pytest.mark.parametrize(("signum", "code", "needle"), [(signal.SIGINT, 130, "interrupted (Ctrl-C)"),
                                                        (signal.SIGTERM, 143, "stopped by SIGTERM")], ids=["ctrl_c", "sigterm"])  # fmt: skip
def test_prepare_stopped_while_it_builds_leaves_no_build_folder_or_lock(tmp_path, signum, code, needle):
    out = tmp_path / "data" / "ds"
    proc = popen_cli(tmp_path, "prepare", *PREPARE, "--out", str(out), stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, text=True, preexec_fn=_as_at_a_terminal)  # fmt: skip
    try:
        building = lambda: out.parent.is_dir() and any(out.parent.glob(".ds.building-*"))  # noqa: E731
        assert wait_for(building, 300) and proc.poll() is None, "prepare ended before it was stopped"
        proc.send_signal(signum)
        stdout, stderr = proc.communicate(timeout=120)
    finally:
        proc.kill()
    completed = subprocess.CompletedProcess(proc.args, proc.returncode, stdout, stderr)
    assert_refused(completed, needle, "the output folder is as it was before", code=code)
    assert sorted(p.name for p in out.parent.iterdir()) == [], "a build folder, a lock or a half dataset was left"


@pytest.mark.parametrize(
    ("stop", "code", "line"),
    [
        (Stopped("stopped by SIGTERM"), 143, "error: stopped by SIGTERM"),
        (KeyboardInterrupt(), 130, "error: interrupted (Ctrl-C)"),
    ],
)
def test_a_signal_that_an_import_turned_into_an_import_error_is_still_the_signal(capsys, stop, code, line):
    # the sampling CLI's SIGTERM test once met it: the signal came during matplotlib's first import of its Agg
    # backend, whose pybind11 initialisation re-raised it as ImportError('initialization failed') from the signal
    def first_import():
        try:
            raise stop
        except BaseException as err:
            raise ImportError("initialization failed") from err

    with pytest.raises(SystemExit) as exit_:
        guarded(first_import)()
    assert exit_.value.code == code and capsys.readouterr().err.strip() == line
    assert signal_behind(ImportError("initialization failed")) is None  # one of its own is no signal


@pytest.mark.parametrize(("signum", "code", "line"), [(signal.SIGTERM, 143, "error: stopped by SIGTERM"),
                                                     (signal.SIGINT, 130, "error: interrupted (Ctrl-C)")])  # fmt: skip
def test_a_signal_that_c_code_dropped_for_another_error_is_still_the_signal(capsys, signum, code, line):
    # CI met it: SIGTERM while matplotlib's Agg renderer drew a video frame came out as ValueError('Invalid bounding
    # box'), with no link to the signal, and the command showed a traceback instead of its one line
    def drawing():
        try:
            os.kill(os.getpid(), signum)
            time.sleep(5)  # the handler raises here
        except BaseException:  # noqa: BLE001 - what the C code does with it
            pass
        raise ValueError("Invalid bounding box")

    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    restore = stop_on_sigterm(kept="")
    try:
        with pytest.raises(SystemExit) as exit_:
            guarded(drawing)()
    finally:
        restore()
        signal.signal(signal.SIGINT, previous)
    assert exit_.value.code == code and capsys.readouterr().err.strip() == line
    with pytest.raises(ValueError, match="bounding box"):  # reported once: the next error is an error again
        guarded(_plain_error)()


def _plain_error():
    raise ValueError("Invalid bounding box")


def test_prepare_called_in_process_gives_the_callers_signal_handlers_back(tmp_path):
    """prepare's main() installs its Ctrl-C and SIGTERM handlers for its run; a program that calls it in-process
    gets its own handlers back, and no signal noted during the run outlives it."""
    from motiondiff.data.preparing.prepare import main

    def callers_handler(signum, frame):
        pass

    previous = signal.signal(signal.SIGTERM, callers_handler), signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        code = main(["bandai", "--src", str(tmp_path / "missing"), "--out", str(tmp_path / "out")])
        assert code == 2
        assert signal.getsignal(signal.SIGTERM) is callers_handler
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
        assert signal_behind(ValueError("later")) is None
    finally:
        signal.signal(signal.SIGTERM, previous[0])
        signal.signal(signal.SIGINT, previous[1])
