"""Bounds on what small inputs may ask for, through the installed commands: BVH files whose frame time, frame count or
joint names ask for too much or lie, zip bombs and members named outside the archive, link loops, num_samples far
beyond the bound (one case of each kind as a subprocess, the others in this process: see hostile_cli). Every refused
case: exit code 2, one ``error:`` line, no traceback, no files left. The largest small inputs run under a
peak-memory measure (the child's peak RSS, `ru_maxrss` of a fresh wrapper process: RLIMIT_AS
cannot limit torch, whose virtual reservations are far above what it uses) and must stay within 4 GiB."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
from bounds_files import bvh_text, npz_bomb, set_line, write, zip_bomb, zip_of
from hostile_cli import Hostile, assert_refused, cli_env, command, files_under

from motiondiff.data.formats.bvh_parse import MAX_VALUES
from motiondiff.pipelines import MotionPipeline

PEAK_LIMIT = 4 * 2**30
EDIT = ("checkpoint=shipped", "num_samples=1", "export=none", "sampler=ddim", "steps=2")
CLIP = "input=test:dataset-1_walk_active_001"


def _bvh(text_fn, name: str = "clip.bvh"):
    def setup(tmp: Path) -> tuple[str, ...]:
        return (f"input={write(tmp / name, text_fn())}",)

    return setup


def edit_bvh(name: str, text_fn, *needles: str, args: tuple[str, ...] = (), process=False) -> Hostile:
    return Hostile(name, "edit", (*EDIT, *args), ("clip.bvh", *needles), _bvh(text_fn), process=process)


def _frame_time(value: str):
    return lambda: set_line(bvh_text(165), "Frame Time", f"Frame Time: {value}")  # 7.6 KB


def _frames(count: int, **kwargs):
    return lambda: set_line(bvh_text(4, **kwargs), "Frames", f"Frames: {count}")


def prepare(name: str, setup, *needles: str, args: tuple[str, ...] = (), process=False) -> Hostile:
    def made(tmp: Path) -> tuple[str, ...]:
        return ("bvh", "--src", str(setup(tmp)), "--out", str(tmp / "out"), "--workers", "1", *args)

    return Hostile(name, "prepare", (), needles, made, process=process)


def _folder(*names_and_texts) -> callable:
    def setup(tmp: Path) -> Path:
        for name, text_fn in names_and_texts:
            write(tmp / "src" / name, text_fn())
        return tmp / "src"

    return setup


def _link_loop(tmp: Path) -> Path:
    write(tmp / "src" / "sub" / "clip.bvh", bvh_text(4))
    os.symlink(tmp / "src", tmp / "src" / "sub" / "up")
    return tmp / "src"


def _broken_link(tmp: Path) -> Path:
    write(tmp / "src" / "clip.bvh", bvh_text(4))
    os.symlink(tmp / "nowhere.bvh", tmp / "src" / "gone.bvh")
    return tmp / "src"


def _bomb(declared: int | None):
    return lambda tmp: zip_bomb(tmp / "bomb.zip", 800 * 2**20, declared)


def _duplicate_joint() -> str:
    return bvh_text(4).replace("JOINT Toes_R", "JOINT Toes_L")


def _turned_root() -> str:
    """Every frame's root turned 90 degrees about x: the body lies along z while its rest pose stands along y."""
    lines = bvh_text(40).split("\n")
    start = lines.index("MOTION") + 3
    lines[start:-1] = [" ".join(row.split()[:4] + ["90.00"] + row.split()[5:]) for row in lines[start:-1]]
    return "\n".join(lines)


def _timed_prompts(tmp: Path) -> tuple[str, ...]:
    (tmp / "timed.txt").write_text("a person walks:2\na person waves:2\n")
    return ("prompts_file=timed.txt",)


CASES = [
    # BVH files that ask for too much or lie: refused with one line, before the model loads
    edit_bvh("edit_frames_beyond_bound", _frames(600000), "'Frames: 600000'", "split the capture", process=True),
    edit_bvh("edit_duplicate_joint_names", _duplicate_joint, "'Toes_L' appears twice", "rename one"),
    edit_bvh("edit_resampled_beyond_bound", lambda: bvh_text(20001, frame_time=10.0), "more than 200000"),
    prepare(
        "prepare_frame_time_huge",
        _folder(("clip.bvh", _frame_time("1e6"))),
        "clip.bvh",
        "outside 0.0001..10",
        process=True,
    ),
    prepare("prepare_frame_time_tiny", _folder(("clip.bvh", _frame_time("0.00001"))), "'Frame Time: 1e-05'"),
    prepare(
        "prepare_values_beyond_bound",
        _folder(("clip.bvh", _frames(MAX_VALUES // 66 + 1, all_channels=True))),
        f"{MAX_VALUES} values",
    ),  # fmt: skip
    prepare("prepare_frames_declared_more", _folder(("clip.bvh", _frames(5))), "expected 5 frames", "truncated"),
    prepare("prepare_frames_declared_fewer", _folder(("clip.bvh", _frames(3))), "more values than 'Frames: 3'"),
    Hostile(
        "edit_npz_bomb",
        "edit",
        EDIT,
        ("joints.npy takes 2048 MB", "more than the 256 MB"),
        lambda tmp: (f"input={npz_bomb(tmp / 'bomb.npz')}",),
    ),  # fmt: skip
    # num_samples beyond the bound: refused before the model loads
    Hostile("edit_num_samples_huge", "edit", (*EDIT[:1], CLIP, "num_samples=100000"), ("num_samples=100000", "1000")),
    Hostile(
        "sample_num_samples_huge",
        "sample",
        ("checkpoint=shipped", "text=walk", "num_samples=100000"),
        ("num_samples=100000", "from 1 to 1000"),
        process=True,
    ),  # fmt: skip
    Hostile(
        "sample_long_num_samples", "sample", ("checkpoint=shipped", "num_samples=65"), ("from 1 to 64",), _timed_prompts
    ),  # fmt: skip
    # archives, folders and the up axis
    prepare(
        "prepare_zip_traversal",
        lambda tmp: zip_of(tmp / "t.zip", {"../../evil.bvh": bvh_text(4)}),
        "'../../evil.bvh' points outside the archive",
    ),  # fmt: skip
    prepare(
        "prepare_zip_duplicate_joints",
        lambda tmp: zip_of(tmp / "d.zip", {"clip.bvh": _duplicate_joint()}),
        "appears twice",
    ),  # fmt: skip
    prepare("prepare_link_loop", _link_loop, "a link loop"),
    prepare("prepare_broken_link", _broken_link, "gone.bvh is a broken link"),
    prepare(
        "prepare_up_axis_unknown", _folder(("clip.bvh", lambda: bvh_text(40))), "--up-axis", args=("--up-axis", "w")
    ),  # fmt: skip
    prepare(
        "prepare_up_axis_undecided", _folder(("clip.bvh", _turned_root)), "cannot tell its up axis", "--up-axis y|z|x"
    ),  # fmt: skip
]

# ---- the largest small inputs, under a peak-memory measure -------------------------------------------------------
_PEAK = "import resource, subprocess, sys; rc = subprocess.call(sys.argv[2:]); " \
        "open(sys.argv[1], 'w').write(str(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)); sys.exit(rc)"  # fmt: skip


def run_measured(tmp: Path, name: str, *args: str) -> tuple[subprocess.CompletedProcess, int]:
    """``motiondiff-<name> *args`` in ``tmp`` through a fresh wrapper process; (the process, the child's peak RSS in
    bytes). Only the command runs under the wrapper, so its peak is the command's own (workers included: the largest
    one's)."""
    peak = tmp.parent / f"{tmp.name}.peak"
    proc = subprocess.run([sys.executable, "-c", _PEAK, str(peak), *command(name), *args], cwd=tmp, env=cli_env(tmp),
                          capture_output=True, text=True, timeout=300)  # fmt: skip
    return proc, int(peak.read_text()) * 1024


def _long_bvh(tmp: Path) -> tuple[str, ...]:
    """470,000 frames at 120 fps (65 minutes, 9.6 MB; frames x joints near the bound), Z-up: 80 frames are edited."""
    return (f"input={write(tmp / 'long.bvh', bvh_text(470000, up='+z', fmt='%.4g'))}", "text=a person walks")


MEASURED = {  # name: (case, refused)
    "edit_7kb_bvh_frame_time_1e6": (edit_bvh("m1", _frame_time("1000000"), "outside"), True),
    "prepare_800mb_zip_bomb": (prepare("m2", _bomb(None), "clip.bvh", "more than the 256 MB"), True),
    "prepare_800mb_zip_bomb_lying": (prepare("m3", _bomb(1000), "does not inflate to the 1000 bytes"), True),
    "edit_470k_frame_z_up_bvh": (Hostile("m4", "edit", EDIT, (), _long_bvh), False),
}


@pytest.fixture(scope="module")
def measured(tmp_path_factory) -> dict:
    def run(item):
        name, (case, _), tmp, extra = item
        return name, (*run_measured(tmp, case.command, *case.args, *extra), tmp)

    items = []  # the setups one after another (see hostile_cli.run_collected: the parser is not thread-safe)
    for name, (case, refused) in MEASURED.items():
        tmp = tmp_path_factory.mktemp(name)
        items.append((name, (case, refused), tmp, case.setup(tmp)))
    with ThreadPoolExecutor(max_workers=2) as pool:
        return dict(pool.map(run, items))


def _assert_nothing_left(tmp: Path) -> None:
    left = files_under(tmp / "outputs") + files_under(tmp / "out")
    assert left == [], f"a failed run left {left}"
    assert not list(tmp.parent.rglob("evil.bvh")), "a member was written outside the archive"


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_refused_in_one_line_leaving_nothing(results, case):
    proc, tmp = results[case.name]
    assert_refused(proc, *case.needles)
    _assert_nothing_left(tmp)


@pytest.mark.parametrize("name", list(MEASURED))
def test_largest_small_inputs_stay_within_4_gib(measured, name):
    proc, peak, tmp = measured[name]
    case, refused = MEASURED[name]
    print(f"{name}: peak RSS {peak / 2**20:.0f} MiB")
    assert peak <= PEAK_LIMIT, f"{name} peaked at {peak / 2**30:.2f} GiB"
    if refused:
        assert_refused(proc, *case.needles)
        _assert_nothing_left(tmp)
        return
    assert proc.returncode == 0 and "Traceback" not in proc.stderr, proc.stderr[-3000:]
    out = next((tmp / "outputs" / "edit").iterdir())
    result = json.loads((out / "results.json").read_text())["input"]
    # the window was cut to the released model's length (and its dropped first frame), not the whole file
    max_frames = int(MotionPipeline.from_pretrained("text").model.hparams.max_frames)
    assert result["window"] == [0, max_frames + 1] and result["total_frames"] == 78334
    assert (tmp / "long.bvh").stat().st_size <= 10**7
    assert result["up_axis"]["axis"] == "+z" and result["up_axis"]["decided"]  # a Z-up file turned to Y-up
