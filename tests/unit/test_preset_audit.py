"""Every paper preset resolves to the settings the papers state (motiondiff.cli.preset_audit), a drifted value is
caught, and docs/presets_audit.md is the audit as generated from the current presets."""

from __future__ import annotations

import pytest

from motiondiff.cli.common import REPO_DIR
from motiondiff.cli.preset_audit import audit, markdown, paper_presets

PRESETS = paper_presets()


def test_there_are_paper_presets_to_audit():
    assert len(PRESETS) >= 30 and "mdm_humanml3d_tab6_t10" in PRESETS and "vvmdm_humanact12_tab1_jp" in PRESETS


@pytest.mark.parametrize("preset", PRESETS)
def test_preset_matches_the_paper(preset):
    rows = audit(preset)
    assert len(rows) >= 18
    differs = [(key, paper, value) for key, paper, _, value in rows if value != paper]
    assert not differs, f"{preset} differs from the paper: {differs}"


@pytest.mark.parametrize(
    ("preset", "override", "key"),
    [("mdm_humanml3d", "trainer=gpu", "trainer.precision"), ("mdm_humanact12_tab3", "condition.drop_prob=0.1",
      "condition.drop_prob"), ("vvmdm_humanact12_tab1_jp", "optim.lr=2e-4", "optim.lr")],
)  # fmt: skip
def test_a_drifted_setting_is_caught(preset, override, key):
    differs = [k for k, paper, _, value in audit(preset, [override]) if value != paper]
    assert differs == [key] or (key in differs and override == "trainer=gpu")


def test_the_committed_audit_table_is_current():
    committed = (REPO_DIR / "docs" / "presets_audit.md").read_text()
    assert committed == markdown(PRESETS), "regenerate it: python -m motiondiff.cli.preset_audit"
