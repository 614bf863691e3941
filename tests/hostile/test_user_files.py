"""Nothing of the user's is overwritten without --force, and a refused run writes nothing (issue 41): `prepare` into
a folder that holds the user's files, two `prepare` runs into one folder at once, and runs aimed at an earlier run's
folder (a finished training run, a sampling run), through the installed commands. Every refusal is exit 2 and one
``error:`` line, and the user's files stay byte-identical."""

from __future__ import annotations

import hashlib
import subprocess
from pathlib import Path

import pytest
from hostile_cli import assert_refused, popen_cli, run_in_process
from kill_runs import BANDAI, PREPARE

needs_bandai = pytest.mark.skipif(not BANDAI.is_file(), reason=f"needs the Bandai Namco data at {BANDAI}")


def snapshot(folder: Path) -> dict[str, str]:
    """Every file under ``folder`` (hidden ones too) by its bytes' hash."""
    return {p.relative_to(folder).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}  # fmt: skip


@needs_bandai
def test_prepare_into_a_folder_of_the_users_files_is_refused_without_force_and_keeps_them_with_it(tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "README.md").write_text("my notes on this data")
    (out / "report.json").write_text('{"my": "report"}')
    (out / "other.txt").write_text("kept either way")
    before = snapshot(tmp_path)
    proc = run_in_process(tmp_path, "prepare", *PREPARE, "--out", str(out))
    assert_refused(proc, "holds report.json, README.md, which the new dataset would replace", "--force")
    assert snapshot(tmp_path) == before, "a refused prepare changed the user's files"
    proc = run_in_process(tmp_path, "prepare", *PREPARE, "--out", str(out), "--force")
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert (out / "meta.json").is_file() and (out / "README.md").read_text() != "my notes on this data"
    assert (out / "other.txt").read_text() == "kept either way"  # a file the dataset does not write stays
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == []  # no lock or build left


@needs_bandai
def test_two_prepares_into_one_folder_at_once_give_one_dataset_and_one_refusal(tmp_path):
    out = tmp_path / "data" / "ds"
    procs = [popen_cli(tmp_path, "prepare", *PREPARE, "--seed", str(seed), "--out", str(out),
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for seed in (0, 1)]  # fmt: skip
    done = [subprocess.CompletedProcess(p.args, p.wait(timeout=600), *p.communicate()) for p in procs]
    codes = sorted(p.returncode for p in done)
    assert codes == [0, 2], [(p.returncode, p.stderr[-1500:]) for p in done]
    refused = next(p for p in done if p.returncode == 2)
    line = assert_refused(refused)
    assert "another prepare" in line or "already holds a prepared dataset" in line, line
    assert (out / "meta.json").is_file()
    assert sorted(p.name for p in out.parent.iterdir()) == ["ds"], "a lock or a build folder was left"


def earlier_run(folder: Path) -> Path:
    """A finished run's folder as the commands leave it: Hydra's records, run.json, results and a checkpoint."""
    (folder / ".hydra").mkdir(parents=True)
    (folder / ".hydra" / "config.yaml").write_text("seed: 0\n")
    (folder / ".hydra" / "overrides.yaml").write_text("- trainer.max_steps=10\n")
    (folder / "run.json").write_text('{"train_steps": 10}')
    (folder / "checkpoints").mkdir()
    (folder / "checkpoints" / "last.ckpt").write_bytes(b"the earlier run's model")
    return folder


@pytest.mark.parametrize(
    "name,args",
    [("train", ("trainer.max_steps=2",)),
     ("sample", ("checkpoint=shipped", "text=a person walks", "length=1", "export=none")),
     ("evaluate", ("checkpoint=shipped", "replications=1"))],
    ids=["train", "sample", "evaluate"],
)  # fmt: skip
def test_a_run_aimed_at_an_earlier_runs_folder_is_refused_before_anything_is_written(tmp_path, name, args):
    run_dir = earlier_run(tmp_path / "runs" / "earlier")
    before = snapshot(tmp_path)
    proc = run_in_process(tmp_path, name, *args, f"hydra.run.dir={run_dir}")
    line = assert_refused(proc, "holds an earlier run", str(run_dir))
    assert f"ckpt_path={run_dir / 'checkpoints' / 'last.ckpt'}" in line  # how to go on training it instead
    assert snapshot(tmp_path) == before, "the refused run rewrote the earlier run's records"


def test_resuming_a_training_run_in_its_own_folder_is_not_refused_as_a_used_folder(tmp_path):
    run_dir = earlier_run(tmp_path / "runs" / "earlier")
    proc = run_in_process(tmp_path, "train", "trainer.max_steps=2", f"hydra.run.dir={run_dir}",
                          f"ckpt_path={run_dir / 'checkpoints' / 'last.ckpt'}")  # fmt: skip
    line = assert_refused(proc, "ckpt_path=")  # the fake checkpoint is refused, by what it holds, not by the folder
    assert "holds an earlier run" not in line
    assert (run_dir / "checkpoints" / "last.ckpt").read_bytes() == b"the earlier run's model"


def test_saving_into_a_folder_of_an_earlier_save_is_refused_unless_asked(tmp_path):
    from motiondiff.pipelines import MotionPipeline
    from motiondiff.runtime.errors import UsageError

    out = MotionPipeline.from_pretrained("text")("a person walks forward", seconds=1, steps=2)
    folder = tmp_path / "walks"
    out.save(folder, formats=["bvh"])
    (folder / "my_notes.txt").write_text("mine")
    before = snapshot(folder)
    with pytest.raises(UsageError, match="already holds a_person_walks_forward_00.bvh, .* pass overwrite=True"):
        out.save(folder, formats=["bvh"])
    assert snapshot(folder) == before
    out.save(folder, formats=["bvh"], overwrite=True)
    assert (folder / "my_notes.txt").read_text() == "mine"


def test_a_run_refused_after_hydra_started_leaves_no_folder_at_all(tmp_path):
    """`length=abc` is refused by the command's own checks, after Hydra made the run folder and its parents: the
    folder goes, and so do the parents this run made (`outputs/sample/`), not only the files."""
    proc = run_in_process(tmp_path, "sample", "checkpoint=shipped", "text=walk", "length=abc")
    assert_refused(proc, "length='abc'")
    assert not (tmp_path / "outputs").exists(), sorted(str(p) for p in (tmp_path / "outputs").rglob("*"))
    (tmp_path / "outputs" / "sample").mkdir(parents=True)
    (tmp_path / "outputs" / "sample" / "mine").mkdir()  # a folder that was there before stays
    assert_refused(run_in_process(tmp_path, "sample", "checkpoint=shipped", "text=walk", "length=abc"), "length")
    assert sorted(p.name for p in (tmp_path / "outputs" / "sample").iterdir()) == ["mine"]
