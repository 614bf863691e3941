"""The wheel carries what an installed motiondiff needs to run from any folder: configs, the released models and
evaluators, the embedded data, and the console scripts."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from motiondiff.model_files.resolve import SHIPPED_MODELS

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    """The wheel built from a copy of this checkout, as the README's wheel line builds it."""
    tmp_path = tmp_path_factory.mktemp("wheel")
    source = tmp_path / "source"  # a copy: building in place would leave build/ and egg-info in the checkout
    for name in ("src", "conf", "checkpoints", "data", "pyproject.toml", "setup.py", "README.md"):
        copy = shutil.copytree if (REPO / name).is_dir() else shutil.copy
        copy(REPO / name, source / name, **({"ignore": shutil.ignore_patterns("bandai", "*.egg-info", "__pycache__")}
                                           if (REPO / name).is_dir() else {}))  # fmt: skip
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q", "-w",
                    str(tmp_path), str(source)], check=True, cwd=tmp_path, capture_output=True)  # fmt: skip
    return next(tmp_path.glob("motiondiff-*.whl"))


@pytest.mark.slow
def test_wheel_bundles_configs_models_data_and_commands(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    bundled = "motiondiff/_bundled/"
    for needed in (
        "conf/sample.yaml",
        "conf/paths/default.yaml",
        f"checkpoints/models/{SHIPPED_MODELS['text'].name}",
        f"checkpoints/models/{SHIPPED_MODELS['text'].stem}.coverage.safetensors",
        "checkpoints/evaluators/bandai_mini/text_motion.safetensors",
        "data/bandai_mini/meta.json",
    ):
        assert bundled + needed in names, needed
    assert "motiondiff/pipelines/__init__.py" in names and not any(
        n.startswith(bundled + "data/bandai/") for n in names
    )
    entry_points = next(n for n in names if n.endswith("entry_points.txt"))
    text = zipfile.ZipFile(wheel).read(entry_points).decode()
    for command in (
        "motiondiff-train",
        "motiondiff-sample",
        "motiondiff-edit",
        "motiondiff-evaluate",
        "motiondiff-prepare",
        "motiondiff-demo",
    ):
        assert command in text


def fresh_venv(folder: Path) -> Path:
    """A new virtual environment whose site-packages links every installed distribution of this one except
    motiondiff itself (installed here editable, from the checkout): the wheel's dependencies are there, as after
    `pip install -c requirements.lock`, with no network and no index; motiondiff comes only from the wheel."""
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(folder)], check=True)
    ours = Path(next(p for p in sys.path if p.endswith("site-packages") and Path(p).is_dir()))
    theirs = next((folder / "lib").glob("python3*/site-packages"))
    for entry in ours.iterdir():
        if not entry.name.startswith(("motiondiff", "__editable__", "_motiondiff")):
            (theirs / entry.name).symlink_to(entry)
    return folder / "bin"


@pytest.mark.slow
def test_wheel_installs_in_a_fresh_venv_and_both_commands_run_from_an_empty_folder(wheel, tmp_path):
    """The README's install path: the built wheel with [demo] into a new venv, offline (--no-index); then
    `motiondiff-sample` as the README gives it and `motiondiff-demo --help`, from an empty folder."""
    bin_dir = fresh_venv(tmp_path / "venv")
    installed = subprocess.run(
        [sys.executable, "-m", "pip", "--python", str(bin_dir / "python"), "install", "-q", "--no-index",
         "--find-links", str(wheel.parent), f"motiondiff[demo] @ {wheel.as_uri()}"],
        capture_output=True, text=True,
    )  # fmt: skip
    assert installed.returncode == 0, installed.stderr[-2000:]
    empty = tmp_path / "empty"
    empty.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env.update(PATH=f"{bin_dir}{os.pathsep}{env.get('PATH', '')}", MPLCONFIGDIR=str(tmp_path / "mpl"),
               WANDB_MODE="offline", HF_HUB_OFFLINE="1", TRANSFORMERS_OFFLINE="1")  # fmt: skip
    where = subprocess.run([bin_dir / "python", "-c", "import motiondiff; print(motiondiff.__file__)"],
                           cwd=empty, env=env, capture_output=True, text=True, check=True)  # fmt: skip
    assert Path(where.stdout.strip()).is_relative_to(tmp_path / "venv"), where.stdout  # the wheel's, not the checkout's
    sample = subprocess.run(
        [bin_dir / "motiondiff-sample", "checkpoint=shipped", "text=a person walks forward", "export=bvh",
         "num_samples=1", "length=2"],
        cwd=empty, env=env, capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert sample.returncode == 0 and "Traceback" not in sample.stderr, sample.stderr[-3000:]
    assert list(empty.glob("outputs/sample/*/*.bvh")), sorted(p.name for p in empty.rglob("*"))
    demo = subprocess.run([bin_dir / "motiondiff-demo", "--help"], cwd=empty, env=env, capture_output=True,
                          text=True, timeout=300)  # fmt: skip
    assert demo.returncode == 0 and "usage: motiondiff-demo" in demo.stdout, demo.stderr[-3000:]
    assert "Traceback" not in demo.stderr
