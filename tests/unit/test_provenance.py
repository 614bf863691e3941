"""Runs record what produced them: the resolved config, the git commit and the package versions."""

from __future__ import annotations

import json
import re

import pytest
from omegaconf import OmegaConf

from motiondiff.runtime.provenance import REPO_DIR, git_state, package_versions, provenance, update_run_json


@pytest.mark.skipif(not (REPO_DIR / ".git").exists(), reason="not a git checkout (a source archive has no commit)")
def test_git_state_names_the_checked_out_commit():
    state = git_state()
    assert re.fullmatch(r"[0-9a-f]{40}", state["commit"]) and isinstance(state["dirty"], bool)


def test_outside_a_checkout_the_commit_is_unknown_not_an_error(tmp_path):
    assert git_state(tmp_path) == {"commit": None, "dirty": None}


def test_versions_of_the_pinned_packages_are_recorded():
    versions = package_versions()
    assert versions["torch"].startswith("2.13.0") and versions["lightning"] == "2.6.6"
    assert package_versions(("no-such-package-xyz",)) == {"no-such-package-xyz": None}


def test_the_config_is_stored_resolved_and_run_json_merges(tmp_path):
    cfg = OmegaConf.create({"batch_size": 64, "model": {"d_model": 128, "ff": "${model.d_model}"}})
    record = provenance(cfg)
    assert record["config"]["model"]["ff"] == 128
    update_run_json(tmp_path, provenance=record)
    update_run_json(tmp_path, train_steps=10)
    saved = json.loads((tmp_path / "run.json").read_text())
    assert saved["train_steps"] == 10 and saved["provenance"]["config"]["batch_size"] == 64
    assert saved["provenance"]["packages"]["torch"].startswith("2.13.0")


def test_the_machine_is_recorded_with_the_instruction_sets_that_decide_its_speed():
    import torch

    from motiondiff.runtime.hardware import cpu_flags, cpu_model

    record = provenance()["machine"]
    assert record["cpu"] == cpu_model() and record["cores"] >= 1 and record["torch_threads"] == torch.get_num_threads()
    assert record["flags"] == [name for name, present in cpu_flags().items() if present]
