"""The 50 cases of the round-3 probe (`probe_round3.py` runs them): what each does, to which surface, and what
a held result looks like. Kept apart from the runner so each file reads as one thing."""

from __future__ import annotations

import json
import os
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests/: the shared fixtures
from fixtures.tiny_bvh import two_joint_bvh  # noqa: E402

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
BVH = two_joint_bvh(hip_height=90)


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
