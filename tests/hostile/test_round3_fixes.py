"""Issue 41's probe (docs/reliability.md, round 3) turned into checks, in this process: `prepare`'s options and
sources, an edit's input path, a prompt that looks like mathtext in a video title, torch's own write errors, and the
demo's start-up options each fail in one line that names the fix, and leave the user's files as they were."""

from __future__ import annotations

import argparse
import json
import os

import pytest
from fixtures.synthetic_motion import glide

from motiondiff.cli.demo import check_args
from motiondiff.data.preparing.prepare import main as prepare_main
from motiondiff.edit.inputs import load_input_motion
from motiondiff.edit.masks import EditError
from motiondiff.export.render import render_motion
from motiondiff.geometry.skeleton import SMPL22
from motiondiff.model_files.loading import load_model
from motiondiff.model_files.resolve import find_model
from motiondiff.runtime.boundary import error_line
from motiondiff.runtime.errors import UsageError


def _prepare(tmp_path, capsys, *args) -> tuple[int, list[str]]:
    (tmp_path / "src").mkdir(exist_ok=True)
    code = prepare_main(["bvh", "--src", str(tmp_path / "src"), "--out", str(tmp_path / "out"), *args])
    return code, [line for line in capsys.readouterr().err.splitlines() if line.startswith("error:")]


@pytest.mark.parametrize("value", ["0", "1", "-5"])
def test_prepare_refuses_a_max_frames_below_two_in_one_line(value, tmp_path, capsys):
    code, errors = _prepare(tmp_path, capsys, "--max-frames", value)
    assert code == 2 and len(errors) == 1 and f"--max-frames {value}: must be a whole number >= 2" in errors[0]
    assert not (tmp_path / "out").exists()


def test_prepare_refuses_bad_units_a_joint_map_list_and_a_pipe(tmp_path, capsys):
    code, errors = _prepare(tmp_path, capsys, "--units-to-metres", "nan")
    assert code == 2 and "--units-to-metres nan: must be a positive number" in errors[0]
    listed = tmp_path / "map.json"
    listed.write_text(json.dumps(["Hips", "Spine"]))
    (tmp_path / "src").mkdir(exist_ok=True)
    (tmp_path / "src" / "a.bvh").write_text((tmp_path / "map.json").read_text())  # any file: the map fails first
    code, errors = _prepare(tmp_path, capsys, "--joint-map", str(listed))
    assert code == 2 and len(errors) == 1 and "must be a JSON object" in errors[0]
    fifo = tmp_path / "pipe.zip"
    os.mkfifo(fifo)
    code = prepare_main(["bvh", "--src", str(fifo), "--out", str(tmp_path / "out")])  # must not block on the pipe
    errors = [line for line in capsys.readouterr().err.splitlines() if line.startswith("error:")]
    assert code == 2 and "is a pipe or device, not a file" in errors[0]
    assert not (tmp_path / "out").exists()


@pytest.fixture(scope="module")
def model():
    return load_model(find_model("text"))


def test_an_edit_input_that_is_no_motion_file_says_what_it_is(model, tmp_path):
    (tmp_path / "clips").mkdir()
    (tmp_path / "empty.npy").write_bytes(b"")
    os.mkfifo(tmp_path / "pipe.bvh")
    (tmp_path / "loop.bvh").symlink_to(tmp_path / "loop.bvh")
    (tmp_path / "notes.txt").write_text("walk")
    (tmp_path / "cut.npy").write_bytes(b"\x93NUMPY\x01\x00v\x00")  # a header cut short
    cases = {"clips": "is a folder", "empty.npy": r"is empty \(0 bytes\)", "pipe.bvh": "is a pipe or device",
             "loop.bvh": "symbolic link that loops", "notes.txt": "is a .txt file; edit reads",
             "cut.npy": "not a readable .npy array", "missing.bvh": "not found"}  # fmt: skip
    for name, message in cases.items():
        with pytest.raises(EditError, match=message):
            load_input_motion(tmp_path / name, model)


def test_a_prompt_that_looks_like_mathtext_is_drawn_as_text(tmp_path):
    path = render_motion(glide(0, 0.5, frames=8), SMPL22, tmp_path / "m.gif", title="$_$ a person {walks}$", size=120)
    assert path.stat().st_size > 0


def test_torch_write_errors_are_one_line_about_the_disk():
    line = error_line(
        RuntimeError("[enforce fail at inline_container.cc:778] . PytorchStreamWriter failed writing file")
    )
    assert line is not None and "free some disk space" in line
    assert error_line(RuntimeError("a bug")) is None  # anything else stays a traceback


def _demo_args(**changes) -> argparse.Namespace:
    return argparse.Namespace(**{"port": 7860, "seconds": 4.0, "steps": 50, "output_dir": None, **changes})


def test_the_demo_checks_its_options_before_loading(tmp_path):
    with pytest.raises(UsageError, match="--port 70000: must be a port number from 1 to 65535"):
        check_args(_demo_args(port=70000))
    (tmp_path / "file").write_text("mine")
    with pytest.raises(UsageError, match="is a file, not a folder"):
        check_args(_demo_args(output_dir=str(tmp_path / "file")))
    assert (tmp_path / "file").read_text() == "mine"
    with pytest.raises(UsageError, match="seconds=-1"):
        check_args(_demo_args(seconds=-1))
    check_args(_demo_args(output_dir=str(tmp_path / "new" / "folder")))
    assert (tmp_path / "new" / "folder").is_dir()


def test_prepare_refuses_an_over_long_out_name_in_one_line(tmp_path, capsys):
    (tmp_path / "src").mkdir()
    code = prepare_main(["bvh", "--src", str(tmp_path / "src"), "--out", str(tmp_path / ("d" * 300))])
    errors = [line for line in capsys.readouterr().err.splitlines() if line.startswith("error:")]
    assert code == 2 and len(errors) == 1 and "has 300 bytes, more than the file system's 255" in errors[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["src"]
