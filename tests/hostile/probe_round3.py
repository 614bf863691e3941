"""Round 3 hostile/careless-user probe (issue 41): 50 cases that neither tests/hostile, tests/bad_inputs nor issue 41's
139 probed cases hold, through the installed commands, the Python API and the web demo's request handlers.

A plain script, not collected by pytest (rerun it after fixes and compare):

    nice -n 19 python tests/hostile/probe_round3.py --out /tmp/probe_round3.json [--only S01,E02] [--keep]

Each case runs alone, as its own process (CLI: the console script; API and demo: ``python -c`` with a small
harness), in a fresh temporary folder that holds its working directory, ``MOTIONDIFF_OUTPUT_DIR``, caches and any
output target, under a wall-clock timeout (60 s, at most 120 s) and a 4 GiB resident-memory watchdog (the project's
bound for small inputs). What a user should get from a refusal: exit code 2, exactly one ``error:`` line naming the
problem, no traceback, nothing left behind; from the API: a ``UsageError`` naming it; from the demo: a "Please fix"
status line. The verdict is computed from what happened:

- held: the expected result (a clean refusal naming the problem, or a correct success);
- weak: clear-ish, but a wrong exit code, not exactly one error line, words that do not name the problem, files
  left behind, or the right words in a non-UsageError exception;
- failed: a traceback, a hang or unbounded work (timeout, >4 GiB), a raw exception, or a silent wrong result
  (a bad value accepted).

Permission cases run the command as ``nobody`` (setpriv) because the probe normally runs as root, for whom mode 000
files are readable.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from probe_round3_cases import BIN, CASES, LONG_NAME, PEAK_LIMIT, REPO, Case  # noqa: E402  (beside this script)

# ---- running one case ----------------------------------------------------------------------------------------------

HARNESS = r"""
import json, sys, traceback
from pathlib import Path
tmp = Path(sys.argv[2])
ns = {"tmp": tmp}
try:
    exec(compile(sys.argv[1], "<case>", "exec"), ns)
    r = ns.get("result")
    value = r if isinstance(r, str) else repr(r)
    out = {"outcome": "returned", "value": value[:600]}
except BaseException as e:
    last = traceback.extract_tb(e.__traceback__)[-1]
    out = {"outcome": "raised", "type": f"{type(e).__module__}.{type(e).__qualname__}", "message": str(e)[:600],
           "where": f"{Path(last.filename).name}:{last.lineno}"}
print("PROBE-RESULT " + json.dumps(out), flush=True)
"""


def _command(case: Case, tmp: Path) -> list[str]:
    if case.kind == "py":
        return [sys.executable, "-c", HARNESS, case.code, str(tmp)]
    name, *args = case.args
    args = [a.replace("{tmp}", str(tmp)) for a in args]
    if name == "prepare":
        return [sys.executable, "-m", "motiondiff.data.preparing.prepare", *args]
    return [str(BIN / f"motiondiff-{name}"), *args]


def _shown(case: Case) -> str:
    """The command as a user would type it (the case folder as <tmp>)."""
    if case.kind == "py":
        return (
            case.code.strip().splitlines()[-1].removeprefix("result = ").replace(repr("walk " * 1000), "'walk ' * 1000")
        )
    name, *args = case.args
    head = "python -m motiondiff.data.preparing.prepare" if name == "prepare" else f"motiondiff-{name}"
    shown = [a.replace("{tmp}", "<tmp>").replace(LONG_NAME, "d*300").replace("9" * 5000, "9*5000").replace("a" * 900, "a*900")
             for a in args]  # fmt: skip
    return " ".join([head, *(a if a and " " not in a and "\n" not in a else repr(a) for a in shown)])


def _rss(pid: int) -> int:
    import psutil

    try:
        root = psutil.Process(pid)
        procs = [root, *root.children(recursive=True)]
    except psutil.Error:
        return 0
    total = 0
    for p in procs:
        try:
            total += p.memory_info().rss
        except psutil.Error:
            pass
    return total


def _snapshot(tmp: Path) -> set[str]:
    return (
        {str(p.relative_to(tmp)) for p in tmp.rglob("*") if not p.is_dir() or p.is_symlink()} if tmp.exists() else set()
    )


def _dirs(tmp: Path) -> set[str]:
    return (
        {str(p.relative_to(tmp)) for p in tmp.rglob("*") if p.is_dir() and not p.is_symlink()}
        if tmp.exists()
        else set()
    )


def _repo_outputs() -> set[str]:
    out = REPO / "outputs"
    return {str(p.relative_to(out)) for p in out.glob("*/*")} if out.exists() else set()


def run_case(case: Case, root: Path) -> dict:
    tmp = Path(tempfile.mkdtemp(prefix=f"{case.id}-", dir=root))
    if case.user == "nobody":
        tmp.chmod(0o777)
    if case.setup:
        case.setup(tmp)
    before, dirs_before = _snapshot(tmp), _dirs(tmp)
    repo_before = _repo_outputs()
    env = {**os.environ, "MOTIONDIFF_OUTPUT_DIR": str(tmp / "outputs"), "MOTIONDIFF_CACHE_DIR": str(tmp / ".cache"),
           "MPLCONFIGDIR": str(tmp / ".mpl"), "HYDRA_FULL_ERROR": "0", "WANDB_MODE": "offline", "WANDB_DIR": str(tmp / ".wandb"),
           "HF_HUB_OFFLINE": "1", "TRANSFORMERS_OFFLINE": "1", "GRADIO_ANALYTICS_ENABLED": "False", **case.env}  # fmt: skip
    cmd = _command(case, tmp)
    if case.user == "nobody":
        env["HOME"] = str(tmp)
        cmd = ["setpriv", "--reuid", "65534", "--regid", "65534", "--clear-groups", *cmd]
    timeout = min(case.timeout, 120)
    start = time.monotonic()
    proc = subprocess.Popen(cmd, cwd=tmp, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            errors="replace", start_new_session=True)  # fmt: skip
    peak, killed = 0, None
    out_chunks: list[str] = []
    err_chunks: list[str] = []
    import threading

    readers = [threading.Thread(target=lambda s, b: b.append(s.read()), args=(proc.stdout, out_chunks), daemon=True),
               threading.Thread(target=lambda s, b: b.append(s.read()), args=(proc.stderr, err_chunks), daemon=True)]  # fmt: skip
    for t in readers:
        t.start()
    while proc.poll() is None:
        peak = max(peak, _rss(proc.pid))
        if peak > PEAK_LIMIT:
            killed = f"resident memory passed {PEAK_LIMIT / 2**30:g} GiB"
        elif time.monotonic() - start > timeout:
            killed = f"no answer in {timeout} s"
        if killed:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
            break
        time.sleep(0.25)
    for t in readers:
        t.join(10)
    seconds = time.monotonic() - start
    stdout, stderr = "".join(out_chunks), "".join(err_chunks)
    left = sorted(_snapshot(tmp) - before)
    left = [f for f in left if not f.startswith((".cache", ".mpl", ".wandb", ".config", ".triton", ".local"))]
    dirs_left = sorted(d for d in _dirs(tmp) - dirs_before if not d.startswith(".") and not any((tmp / d).iterdir()))
    row = {"id": case.id, "surface": case.surface, "case": case.what, "command": _shown(case), "expect": case.expect,
           "exit": proc.returncode, "seconds": round(seconds, 1), "peak_rss_mib": round(peak / 2**20),
           "killed": killed, "files_left": left[:20], "n_files_left": len(left), "empty_dirs_left": dirs_left[:10],
           "repo_outputs_changed": sorted(_repo_outputs() ^ repo_before)}  # fmt: skip
    if case.kind == "py" and case.surface in ("API", "demo") and not (case.surface == "demo" and case.kind == "cli"):
        row.update(_judge_py(case, tmp, stdout, stderr, row))
    else:
        row.update(_judge_cli(case, tmp, stdout, stderr, row))
    row.setdefault("message_full", row.get("message", ""))
    row["stderr_tail"] = stderr[-1500:]
    if os.environ.get("PROBE_KEEP") != "1":
        _remove(tmp)
    return row


def _remove(tmp: Path) -> None:
    for p in [tmp, *tmp.rglob("*")]:
        try:
            if p.is_dir() and not p.is_symlink():
                p.chmod(0o755)
        except OSError:
            pass
    shutil.rmtree(tmp, ignore_errors=True)


def _message(text: str) -> str:
    return " ".join(text.split())[:160]


def _judge_cli(case: Case, tmp: Path, stdout: str, stderr: str, row: dict) -> dict:
    errors = [line for line in stderr.splitlines() if line.startswith("error: ")]
    tail = [line for line in stderr.splitlines() if line.strip()]
    message = errors[0] if errors else (tail[-1] if tail else (stdout.strip().splitlines() or [""])[-1])
    traceback_seen = "Traceback (most recent call last)" in stdout + stderr
    out = {
        "error_lines": len(errors),
        "traceback": traceback_seen,
        "message": _message(message),
        "message_full": " ".join(message.split())[:600],
    }
    reasons: list[str] = []
    if row["killed"]:
        cause = case.on_timeout if case.on_timeout and "no answer" in row["killed"] else f"killed: {row['killed']}"
        return {**out, "verdict": "failed", "cause": cause}
    if traceback_seen:
        return {**out, "verdict": "failed", "cause": "a traceback"}
    rc = row["exit"]
    if rc == 0:
        if case.expect == "refuse":
            return {**out, "verdict": "failed", "cause": "accepted (exit 0): silently used or ignored"}
        wrong = case.check(tmp, stdout + stderr) if case.check else None
        if wrong:
            return {**out, "verdict": case.wrong, "cause": f"exit 0 but {wrong}"}
        return {**out, "verdict": "held", "cause": "ran and wrote what was asked"}
    if case.expect == "succeed":
        reasons.append(f"refused a valid input (exit {rc})")
    if rc != 2:
        reasons.append(f"exit {rc}, not 2")
    if len(errors) != 1:
        reasons.append(f"{len(errors)} 'error:' lines")
    missing = [n for n in case.needles if n.lower() not in message.lower()]
    if missing and case.expect != "succeed":
        reasons.append(f"message does not name {missing}")
    misleading = [w for w in case.avoid if w.lower() in message.lower()]
    if misleading:
        reasons.append(f"misleading: says {misleading}")
    if row["n_files_left"] and case.expect != "succeed":
        reasons.append(f"left {row['n_files_left']} file(s)")
    if not reasons:
        return {**out, "verdict": "held", "cause": "one line naming the problem, exit 2, nothing left"}
    return {**out, "verdict": "weak", "cause": "; ".join(reasons)}


def _judge_py(case: Case, tmp: Path, stdout: str, stderr: str, row: dict) -> dict:
    line = next((ln for ln in stdout.splitlines() if ln.startswith("PROBE-RESULT ")), None)
    if row["killed"]:
        return {
            "error_lines": 0,
            "traceback": False,
            "message": "",
            "verdict": "failed",
            "cause": f"killed: {row['killed']}",
        }
    if line is None:
        tail = [ln for ln in stderr.splitlines() if ln.strip()]
        return {"error_lines": 0, "traceback": "Traceback" in stderr, "message": _message(tail[-1] if tail else ""),
                "verdict": "failed", "cause": f"the process died (exit {row['exit']})"}  # fmt: skip
    res = json.loads(line.removeprefix("PROBE-RESULT "))
    if case.surface == "demo":
        return _judge_demo(case, res, row)
    if res["outcome"] == "returned":
        out = {"error_lines": 0, "traceback": False, "message": _message(res["value"])}
        if case.expect == "refuse":
            return {**out, "verdict": "failed", "cause": "returned: the bad value was silently accepted"}
        wrong = case.check(tmp, res["value"]) if case.check else None
        if wrong:
            return {**out, "verdict": case.wrong, "cause": f"returned but {wrong}"}
        return {**out, "verdict": "held", "cause": "accepted and did what was asked"}
    kind = res["type"].rsplit(".", 1)[-1]
    out = {"error_lines": 1, "traceback": kind != "UsageError",
           "message": _message(f"{kind}: {res['message']} [{res['where']}]"),
           "message_full": " ".join(f"{kind}: {res['message']} [{res['where']}]".split())}  # fmt: skip
    named = all(n.lower() in res["message"].lower() for n in case.needles)
    misleading = [w for w in case.avoid if w.lower() in res["message"].lower()]
    left = row["n_files_left"]
    if kind == "UsageError":
        reasons = ([] if named else [f"message does not name {list(case.needles)}"]) + (
            [f"left {left} file(s)"] if left else []
        )
        reasons += [f"misleading: says {misleading}"] if misleading else []
        return {
            **out,
            "verdict": "weak" if reasons else "held",
            "cause": "; ".join(reasons) or "UsageError naming the problem",
        }
    if named:
        return {**out, "verdict": "weak", "cause": f"raw {kind} (not UsageError), though it names the problem"}
    return {**out, "verdict": "failed", "cause": f"raw {kind} from {res['where']}"}


def _judge_demo(case: Case, res: dict, row: dict) -> dict:
    """A request refused by Gradio's own input checks shows their message in the page (held when it names the
    problem); the page's handler shows "Please fix: ..." for a UsageError and "Generation failed: ..." for a bug."""
    left = [f for f in row["files_left"] if f.startswith("demo_out")]
    if res["outcome"] == "raised":
        kind = res["type"].rsplit(".", 1)[-1]
        out = {"error_lines": 1, "traceback": False, "message": _message(f"{kind}: {res['message']}")}
        if kind == "AppError" and all(n.lower() in res["message"].lower() for n in case.needles):
            return {**out, "verdict": "held", "cause": "refused by the page's input check, naming the value"}
        if kind == "AppError":
            return {
                **out,
                "verdict": "weak",
                "cause": f"refused by Gradio before any work, but does not name {list(case.needles)}",
            }
        return {**out, "traceback": True, "verdict": "failed", "cause": f"{kind} without the problem named"}
    status = res["value"]
    out = {"error_lines": 1 if "fix:**" in status or "failed:**" in status else 0, "traceback": False,
           "message": _message(status)}  # fmt: skip
    if case.expect == "succeed":
        wrong = case.check(None, status) if case.check else None
        return {**out, "verdict": case.wrong if wrong else "held", "cause": wrong or "as expected"}
    if status.startswith("**Please fix:**"):
        named = all(n.lower() in status.lower() for n in case.needles)
        reasons = ([] if named else [f"status does not name {list(case.needles)}"]) + (
            [f"left {len(left)} file(s)/folder(s) in the demo's output folder"] if left else []
        )
        return {**out, "verdict": "weak" if reasons else "held", "cause": "; ".join(reasons) or "a 'Please fix' line"}
    if "failed:**" in status:
        return {**out, "verdict": "failed", "cause": "the bug path: 'Generation failed: <exception>'"}
    return {**out, "verdict": "failed", "cause": "generated: the bad value was silently accepted"}


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", required=True, help="where to write the results (JSON)")
    p.add_argument("--only", default="", help="comma-separated case ids")
    p.add_argument("--keep", action="store_true", help="keep each case's folder (printed)")
    p.add_argument("--workdir", default=None, help="where the case folders go (default: a fresh temporary folder)")
    args = p.parse_args()
    if args.keep:
        os.environ["PROBE_KEEP"] = "1"
    wanted = {c.strip() for c in args.only.split(",") if c.strip()}
    cases = [c for c in CASES if not wanted or c.id in wanted]
    root = Path(args.workdir or tempfile.mkdtemp(prefix="probe_round3-"))
    root.mkdir(parents=True, exist_ok=True)
    root.chmod(0o755)
    rows = []
    for case in cases:
        row = run_case(case, root)
        rows.append(row)
        print(f"{row['id']:4} {row['verdict']:6} exit={row['exit']} {row['seconds']:5.1f}s  {row['cause'][:70]} | {row['message'][:90]}",
              flush=True)  # fmt: skip
        Path(args.out).write_text(json.dumps(_summary(rows), indent=1, ensure_ascii=False))
    summary = _summary(rows)
    Path(args.out).write_text(json.dumps(summary, indent=1, ensure_ascii=False))
    print(json.dumps(summary["counts"]))
    return 0


def _cpu() -> str:
    try:
        names = [ln.split(":", 1)[1].strip() for ln in open("/proc/cpuinfo") if ln.startswith("model name")]
    except OSError:
        names = []
    return f"{names[0] if names else 'unknown CPU'}, {os.cpu_count()} cores"


def _summary(rows: list[dict]) -> dict:
    counts = {v: sum(r["verdict"] == v for r in rows) for v in ("held", "weak", "failed")}
    return {"probe": "round 3 (issue 41)", "date": time.strftime("%Y-%m-%d"), "python": sys.version.split()[0],
            "user": os.getuid(), "cpu": _cpu(),
            "counts": counts, "cases": rows}  # fmt: skip


if __name__ == "__main__":
    sys.exit(main())
