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
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]
BIN = Path(sys.executable).parent
PEAK_LIMIT = 4 * 2**30
MODEL = "checkpoint=shipped"
SMALL = ("num_samples=1", "length=1", "export=none", "sampler=ddim", "steps=2")
CLIP = "input=test:dataset-1_walk_active_001"
TIMED = "prompts=[a person walks forward:2, a person waves both hands:2]"

# ---- the cases -----------------------------------------------------------------------------------------------------


@dataclass
class Case:
    id: str
    surface: str  # CLI | API | demo
    what: str  # one line: the hostile or careless thing
    kind: str  # cli | py
    args: tuple[str, ...] = ()  # cli: the command name then its arguments ({tmp} is the case folder)
    code: str = ""  # py: the snippet (``tmp`` is the case folder as a Path; assign ``result``)
    expect: str = "refuse"  # refuse | succeed | either
    needles: tuple[str, ...] = ()  # words the error line (or exception) must hold to name the problem
    avoid: tuple[str, ...] = ()  # words that would mislead (say something untrue about the input)
    setup: Callable[[Path], None] | None = None
    check: Callable[[Path, str], str | None] | None = None  # success: None if right, else what is wrong
    timeout: int = 60
    wrong: str = "failed"  # the verdict when a success's check finds it wrong
    on_timeout: str = ""  # what a timeout means for this case (a server that started)
    user: str = "root"  # root | nobody
    env: dict = field(default_factory=dict)


def _write(name: str, data: bytes | str) -> Callable[[Path], None]:
    def setup(tmp: Path) -> None:
        path = tmp / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data if isinstance(data, bytes) else data.encode())

    return setup


def _npy(name: str, array: np.ndarray) -> Callable[[Path], None]:
    def setup(tmp: Path) -> None:
        np.save(tmp / name, array, allow_pickle=True)

    return setup


def _fifo(name: str) -> Callable[[Path], None]:
    return lambda tmp: os.mkfifo(tmp / name)


def _truncated_npy(tmp: Path) -> None:
    """A valid .npy header declaring (100000, 22, 3) float32 (26 MB) followed by 100 bytes."""
    header = {"descr": "<f4", "fortran_order": False, "shape": (100000, 22, 3)}
    with open(tmp / "big.npy", "wb") as f:
        np.lib.format.write_array_header_1_0(f, header)
        f.write(b"\0" * 100)


def _self_link(tmp: Path) -> None:
    os.symlink("loop.bvh", tmp / "loop.bvh")


from bounds_files import bvh_text  # noqa: E402  (tests/hostile: a BVH of a full human rig)

RIG_BVH = bvh_text(40)  # 40 frames of a mappable human rig: the prepare cases fail only on what they test
BVH = """HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT Spine
  {
    OFFSET 0 10 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    End Site
    {
      OFFSET 0 10 0
    }
  }
}
MOTION
Frames: 3
Frame Time: 0.033333
0 90 0 0 0 0 0 0 0
0 90 0 0 0 0 0 0 0
0 90 0 0 0 0 0 0 0
"""


def _unreadable_bvh(tmp: Path) -> None:
    (tmp / "private.bvh").write_text(BVH)
    (tmp / "private.bvh").chmod(0)


def _unreadable_src(tmp: Path) -> None:
    (tmp / "src").mkdir()
    (tmp / "src" / "a.bvh").write_text(RIG_BVH)
    (tmp / "src").chmod(0)


def _src_with(*files: tuple[str, str]) -> Callable[[Path], None]:
    def setup(tmp: Path) -> None:
        (tmp / "src").mkdir(exist_ok=True)
        for name, text in files:
            (tmp / name).write_text(text)

    return setup


def _files_named(pattern_ok: Callable[[str], bool], what: str) -> Callable[[Path, str], str | None]:
    def check(tmp: Path, _out: str) -> str | None:
        names = [p.name for p in tmp.rglob("*") if p.is_file()]
        bad = [n for n in names if not pattern_ok(n)]
        return f"{what}: {bad[:2]}" if bad else None

    return check


def _results_in(sub: str) -> Callable[[Path, str], str | None]:
    def check(tmp: Path, _out: str) -> str | None:
        found = list((tmp / sub).rglob("results.json")) if (tmp / sub).exists() else []
        return None if found else f"no results.json under {sub}"

    return check


def _prompt_count(n: int) -> Callable[[Path, str], str | None]:
    def check(tmp: Path, _out: str) -> str | None:
        found = list(tmp.rglob("results.json"))
        if not found:
            return "no results.json"
        rows = json.loads(found[0].read_text())["samples"]
        return None if len(rows) == n else f"{len(rows)} samples written, expected {n}: {[r['prompt'] for r in rows]}"

    return check


LONG_NAME = "d" * 300  # one path component beyond NAME_MAX (255)
ODD_NAME = "odd name ünï $HOME ;` \u202e"

API_HEAD = """
from motiondiff.pipelines import MotionPipeline
pipe = MotionPipeline.from_pretrained("text")
"""
API_OUT = API_HEAD + 'out = pipe("a person walks forward", seconds=2, sampler="ddim", steps=2)\n'

DEMO_HEAD = """
from gradio_client import Client
from motiondiff.demo import DemoModels, build_demo
models = DemoModels()
(tmp / "demo_out").mkdir()
demo = build_demo(models, "text", steps=2, output_dir=tmp / "demo_out")
demo.queue()
_, url, _ = demo.launch(server_name="127.0.0.1", prevent_thread_lock=True, quiet=True)
client = Client(url, verbose=False)
"""


def _demo_call(key: str, seconds: str, guidance: str = "2.0", text: str = "a person walks forward") -> str:
    """One Generate request through Gradio's own request handling (its input checks, then the page's handler), as
    the page sends it; ``result`` is the status line the page shows."""
    return DEMO_HEAD + (f'result = client.predict({key!r}, {text!r}, None, {seconds}, {guidance}, 0, 1, 2, "", '
                        'api_name="/on_generate")[0]\n')  # fmt: skip


CASES = [
    # ---- sample.py: settings of odd types, sizes and interpolations ------------------------------------------------
    Case("S01", "CLI", "sample: guidance given as a boolean", "cli", ("sample", MODEL, "text=walk", *SMALL, "guidance=true"),
         needles=("guidance",)),
    Case("S02", "CLI", "sample: text of zero-width spaces only", "cli", ("sample", MODEL, *SMALL, "text='\u200b\u200b\u200b'"),
         needles=("empty",)),
    Case("S03", "CLI", "sample: a newline inside the prompt, export=bvh", "cli",
         ("sample", MODEL, *SMALL[:-3], "sampler=ddim", "steps=2", "export=bvh", "text='a person walks\nrm -rf x'"),
         expect="either", check=_files_named(lambda n: "\n" not in n and "/" not in n, "file name with a newline"), timeout=120),
    Case("S04", "CLI", "sample: precision=fp16 (not a choice)", "cli", ("sample", MODEL, "text=walk", *SMALL, "precision=fp16"),
         needles=("precision",)),
    Case("S05", "CLI", "sample: sampler.steps=-3 (the nested key, not steps=)", "cli",
         ("sample", MODEL, "text=walk", *SMALL[:3], "sampler=ddim", "sampler.steps=-3"), needles=("steps",)),
    Case("S06", "CLI", "sample: timed prompts with blend=3 > overlap=1", "cli", ("sample", MODEL, TIMED, "num_samples=1", "export=none",
         "sampler=ddim", "steps=2", "blend=3", "overlap=1"), needles=("blend",)),
    Case("S07", "CLI", "sample: run folder with a 300-character name", "cli",
         ("sample", MODEL, "text=walk", *SMALL, f"hydra.run.dir={{tmp}}/outputs/{LONG_NAME}"), needles=("run",)),
    Case("S08", "CLI", "sample: run folder name with spaces, unicode, $, ;, backtick, RLO", "cli",
         ("sample", MODEL, "text=walk", *SMALL, f"hydra.run.dir='{{tmp}}/outputs/{ODD_NAME}'"), expect="succeed",
         check=lambda tmp, out: None if (tmp / "outputs" / ODD_NAME / "results.json").exists() else "no results.json in the named folder",
         timeout=120),
    Case("S09", "CLI", "sample: length from ${oc.env:PROBE_LEN} holding 'abc'", "cli",
         ("sample", MODEL, "text=walk", *SMALL[:1], "export=none", "length=${oc.env:PROBE_LEN}"), needles=("length",),
         env={"PROBE_LEN": "abc"}),
    Case("S10", "CLI", "sample: paths.output_dir=${oc.env:PROBE_UNSET} (variable not set)", "cli",
         ("sample", MODEL, "text=walk", *SMALL, "paths.output_dir=${oc.env:PROBE_UNSET}"), needles=("PROBE_UNSET",)),
    Case("S11", "CLI", "sample: -m seed=range(0,1000000) (a million-job sweep)", "cli",
         ("sample", "-m", MODEL, "text=walk", *SMALL, "seed=range(0,1000000)"), needles=("seed",)),
    Case("S12", "CLI", "sample: length= a 5000-digit number", "cli", ("sample", MODEL, "text=walk", *SMALL[:1], "export=none", "length=" + "9" * 5000),
         needles=("length",)),
    Case("S13", "CLI", "sample: a 900-character one-word prompt with export=bvh (file names > 255 bytes)", "cli",
         ("sample", MODEL, *SMALL[:-3], "sampler=ddim", "steps=2", "export=bvh", "text=" + "a" * 900), expect="either",
         check=_files_named(lambda n: len(n.encode()) <= 255, "a file name over 255 bytes"), timeout=120),
    # ---- edit.py: input files ------------------------------------------------------------------------------------
    Case("E01", "CLI", "edit: input= a folder", "cli", ("edit", MODEL, "input={tmp}/clips", "num_samples=1", "export=none"),
         needles=("clips", "folder"), setup=lambda tmp: (tmp / "clips").mkdir()),
    Case("E02", "CLI", "edit: input= a FIFO named clip.bvh (nothing ever writes it)", "cli",
         ("edit", MODEL, "input={tmp}/clip.bvh", "num_samples=1", "export=none"), needles=("clip.bvh",), avoid=("not found",), setup=_fifo("clip.bvh")),
    Case("E03", "CLI", "edit: input= an empty (0-byte) .npy", "cli", ("edit", MODEL, "input={tmp}/empty.npy", "num_samples=1", "export=none"),
         needles=("empty.npy",), setup=_write("empty.npy", b"")),
    Case("E04", "CLI", "edit: input= an object-dtype .npy (needs pickle)", "cli", ("edit", MODEL, "input={tmp}/obj.npy", "num_samples=1", "export=none"),
         needles=("obj.npy",), setup=_npy("obj.npy", np.array([{"a": 1}, None], dtype=object))),
    Case("E05", "CLI", "edit: input= joints .npy of 0 frames (0, 22, 3)", "cli", ("edit", MODEL, "input={tmp}/zero.npy", "num_samples=1", "export=none"),
         needles=("zero.npy",), setup=_npy("zero.npy", np.zeros((0, 22, 3), np.float32))),
    Case("E06", "CLI", "edit: input= joints .npy with 5 joints (60, 5, 3)", "cli", ("edit", MODEL, "input={tmp}/five.npy", "num_samples=1", "export=none"),
         needles=("five.npy", "joints"), setup=_npy("five.npy", np.random.default_rng(0).normal(size=(60, 5, 3)).astype(np.float32))),
    Case("E07", "CLI", "edit: input= .npy whose header declares (100000, 22, 3) but holds 100 bytes", "cli",
         ("edit", MODEL, "input={tmp}/big.npy", "num_samples=1", "export=none"), needles=("big.npy",), setup=_truncated_npy),
    Case("E08", "CLI", "edit: input= a symlink to itself (loop.bvh -> loop.bvh)", "cli",
         ("edit", MODEL, "input={tmp}/loop.bvh", "num_samples=1", "export=none"), needles=("loop.bvh",), avoid=("not found",), setup=_self_link),
    Case("E09", "CLI", "edit: start=1e9 seconds into a 5 s clip", "cli", ("edit", MODEL, CLIP, "start=1e9", "num_samples=1", "export=none"),
         needles=("start",)),
    Case("E10", "CLI", "edit: input= a mode-000 BVH, run as nobody", "cli", ("edit", MODEL, "input={tmp}/private.bvh", "num_samples=1", "export=none"),
         needles=("private.bvh",), avoid=("write to",), setup=_unreadable_bvh, user="nobody"),
    # ---- evaluate.py ---------------------------------------------------------------------------------------------
    Case("V01", "CLI", "evaluate: split=nonsense", "cli", ("evaluate", MODEL, "split=nonsense", "wandb=false", "replications=1"),
         needles=("nonsense",), timeout=120),
    # ---- prepare -------------------------------------------------------------------------------------------------
    Case("R01", "CLI", "prepare bvh --units-to-metres nan", "cli",
         ("prepare", "bvh", "--src", "{tmp}/src", "--out", "{tmp}/out", "--workers", "1", "--units-to-metres", "nan"),
         needles=("units",), setup=_src_with(("src/a.bvh", RIG_BVH))),
    Case("R02", "CLI", "prepare bvh --labels an empty (0-byte) CSV", "cli",
         ("prepare", "bvh", "--src", "{tmp}/src", "--out", "{tmp}/out", "--workers", "1", "--labels", "{tmp}/labels.csv"),
         needles=("labels.csv",), setup=_src_with(("src/a.bvh", RIG_BVH), ("labels.csv", ""))),
    Case("R03", "CLI", "prepare bvh --labels CSV without the required 'file' column", "cli",
         ("prepare", "bvh", "--src", "{tmp}/src", "--out", "{tmp}/out", "--workers", "1", "--labels", "{tmp}/labels.csv"),
         needles=("file",), setup=_src_with(("src/a.bvh", RIG_BVH), ("labels.csv", "name,action\na.bvh,walk\n"))),
    Case("R04", "CLI", "prepare bvh --joint-map a JSON list, not a mapping", "cli",
         ("prepare", "bvh", "--src", "{tmp}/src", "--out", "{tmp}/out", "--workers", "1", "--joint-map", "{tmp}/map.json"),
         needles=("map.json",), setup=_src_with(("src/a.bvh", RIG_BVH), ("map.json", "[1, 2, 3]"))),
    Case("R05", "CLI", "prepare bvh --src a FIFO named clips.zip", "cli",
         ("prepare", "bvh", "--src", "{tmp}/clips.zip", "--out", "{tmp}/out", "--workers", "1"), needles=("clips.zip",),
         avoid=("no such file", "not found"), setup=_fifo("clips.zip")),
    Case("R06", "CLI", "prepare bvh --src an empty folder", "cli", ("prepare", "bvh", "--src", "{tmp}/src", "--out", "{tmp}/out", "--workers", "1"),
         needles=("src",), setup=_src_with()),
    Case("R07", "CLI", "prepare bvh --out with a 300-character folder name", "cli",
         ("prepare", "bvh", "--src", "{tmp}/src", "--out", f"{{tmp}}/{LONG_NAME}", "--workers", "1"), needles=("out",),
         setup=_src_with(("src/a.bvh", RIG_BVH))),
    Case("R08", "CLI", "prepare bvh --src a mode-000 folder, run as nobody", "cli",
         ("prepare", "bvh", "--src", "{tmp}/src", "--out", "{tmp}/out", "--workers", "1"), needles=("src",), setup=_unreadable_src,
         user="nobody"),
    # ---- the Python API ------------------------------------------------------------------------------------------
    Case("A01", "API", 'MotionPipeline.from_pretrained("")', "py", code='from motiondiff.pipelines import MotionPipeline\n'
         'result = MotionPipeline.from_pretrained("")\n', needles=("model",),
         avoid=("is a folder",)),
    Case("A02", "API", 'MotionPipeline.from_pretrained("text", precision="fp16")', "py",
         code='from motiondiff.pipelines import MotionPipeline\nresult = MotionPipeline.from_pretrained("text", precision="fp16")\n',
         needles=("precision",)),
    Case("A03", "API", 'pipe("a person walks", seconds="2") (seconds as a string)', "py",
         code=API_HEAD + 'result = pipe("a person walks", seconds="2", sampler="ddim", steps=2)\n', expect="either", needles=("seconds",)),
    Case("A04", "API", 'pipe("a person walks", num_samples=True)', "py",
         code=API_HEAD + 'result = pipe("a person walks", seconds=1, num_samples=True, sampler="ddim", steps=2)\n', needles=("num_samples",)),
    Case("A05", "API", 'pipe("a person walks", frames=0.5)', "py",
         code=API_HEAD + 'result = pipe("a person walks", frames=0.5, sampler="ddim", steps=2)\n', needles=("frames",)),
    Case("A06", "API", "out.smoothed(-1) (a negative filter width)", "py", code=API_OUT + "result = out.smoothed(-1)\n",
         needles=("sigma",)),
    Case("A07", "API", "pipe.inbetween(out, prefix=2.5) (a fraction above 1, not whole frames)", "py",
         code=API_OUT + 'result = pipe.inbetween(out, "a person walks", prefix=2.5, sampler="ddim", steps=2)\n', needles=("prefix",)),
    Case("A08", "API", "pipe.edit_parts(out, parts=[])", "py",
         code=API_OUT + 'result = pipe.edit_parts(out, "a person waves", parts=[], sampler="ddim", steps=2)\n', needles=("part",)),
    Case("A09", "API", 'pipe.long(["walk:2", "run:2"], mode="bogus")', "py",
         code=API_HEAD + 'result = pipe.long(["a person walks:2", "a person runs:2"], mode="bogus", sampler="ddim", steps=2)\n',
         needles=("mode",)),
    Case("A10", "API", 'out.save(folder, formats=["BVH"]) (upper case)', "py",
         code=API_OUT + 'result = out.save(tmp / "saved", formats=["BVH"])\n', expect="either", needles=("BVH",),
         check=lambda tmp, out: None if list((tmp / "saved").glob("*.bvh")) else "no .bvh written"),
    Case("A11", "API", "out.to_bvh(5) on a one-motion output", "py", code=API_OUT + "result = out.to_bvh(5)\n", needles=("5",)),
    # ---- the web demo's request handlers, in process (no browser) ------------------------------------------------
    Case("D01", "demo", "demo Generate request: a 5000-character prompt", "py", code=_demo_call("text", "2.0", text="walk " * 1000),
         needles=("1000",), timeout=120),
    Case("D02", "demo", "demo Generate request: seconds=1e9", "py", code=_demo_call("text", "1e9"), needles=("seconds",), timeout=120),
    Case("D03", "demo", "demo model list offers only models", "py",
         code="from motiondiff.demo import DemoModels\nresult = [c.key for c in DemoModels().choices]\n", expect="succeed",
         check=lambda tmp, value: "coverage banks offered as models (choosing one loads bandai_text_cpu under that name): " + value
         if ".coverage" in value else None, wrong="weak"),
    Case("D04", "demo", "demo Edit request before any Generate", "py",
         code=DEMO_HEAD + 'result = client.predict("text", "a person raises both hands", None, ["upper_body"], 2.0, 0, 2, api_name="/on_edit")[0]\n',
         needles=("generate",), timeout=120),
    Case("D05", "demo", "demo started with an output folder that does not exist yet, then a plain Generate", "py",
         code=DEMO_HEAD.replace('(tmp / "demo_out").mkdir()', "").replace('"demo_out"', '"new_folder"')
         + 'result = client.predict("text", "a person walks forward", None, 2.0, 2.0, 0, 1, 2, "", api_name="/on_generate")[0]\n',
         expect="succeed", check=lambda tmp, value: None if value.startswith("Generated") else "the request failed", timeout=120),
    Case("D06", "demo", "motiondiff-demo --port 70000", "cli", ("demo", "--port", "70000", "--output-dir", "{tmp}/demo_out"),
         needles=("port",)),
    Case("D07", "demo", "motiondiff-demo --output-dir an existing file", "cli", ("demo", "--port", "7391", "--output-dir", "{tmp}/taken"),
         needles=("taken",), setup=_write("taken", "a file, not a folder\n"),
         on_timeout="started serving with the bad setting (killed at 60 s)"),
]  # fmt: skip

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
