"""`--help` explains (issue 42): each Hydra command lists its settings and config groups from its own config file,
each with its default and a one-line description; `key=a,b` outside a sweep says how to write a list."""

from __future__ import annotations

import os
import re

import pytest
from fixtures.in_process import call_main

from motiondiff.cli import entry


def _help(tmp_path, command: str) -> str:
    proc = call_main(getattr(entry, command), [f"{command}.py", "--help"], tmp_path, dict(os.environ))
    assert proc.returncode == 0 and proc.stderr == "", proc.stderr
    return proc.stdout


def test_sample_help_lists_its_switches_with_what_each_does(tmp_path):
    text = _help(tmp_path, "sample")
    described = re.findall(r"^  (\w[\w.]*)=\S*\s+(\S.*)$", text, re.MULTILINE)
    assert len(described) >= 15, text
    keys = dict(described)
    assert "checkpoint" in keys and "shipped" in keys["checkpoint"]
    assert "guidance" in keys and "classifier-free" in keys["guidance"]
    assert "sampler=auto" in text and "ddim" in text.split("sampler=auto", 1)[1].splitlines()[0]
    assert not (tmp_path / "outputs").exists()  # help runs nothing


@pytest.mark.parametrize("command", ["train", "edit", "evaluate", "train_vae", "train_latent"])
def test_every_command_has_help_with_its_groups_and_settings(tmp_path, command):
    text = _help(tmp_path, command)
    assert "settings (key=value" in text and len(re.findall(r"^  \w[\w.]*=", text, re.MULTILINE)) >= 5, text


def test_a_list_written_without_brackets_is_told_how_to_write_it(tmp_path):
    proc = call_main(entry.sample, ["sample.py", "checkpoint=shipped", "export=mp4,bvh"], tmp_path, dict(os.environ))
    errors = [line for line in proc.stderr.splitlines() if line.startswith("error:")]
    assert proc.returncode == 2 and len(errors) == 1, proc.stderr
    assert "'export=[mp4,bvh]'" in errors[0] and "-m" in errors[0]
