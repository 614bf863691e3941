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


def test_paper_unet_has_about_the_papers_parameter_count():
    """MDM Table 1 gives the U-Net 23.47 M parameters (no layout): the preset's denoiser, CLIP excluded, is within 5%."""
    from fixtures.tiny_models import tiny_datamodule
    from hydra import compose, initialize_config_dir

    from motiondiff.cli.train import build_module

    with initialize_config_dir(config_dir=str(REPO_DIR / "conf"), version_base="1.3"):
        cfg = compose("train", overrides=["experiment=mdm_humanml3d_tab1_unet", "text_encoder=minilm"])
    denoiser = build_module(cfg, tiny_datamodule()).denoiser
    clip_width_extra = (512 - cfg.text_encoder.dim) * cfg.model.d_model  # CLIP's 512-d features in the projection
    params = sum(p.numel() for p in denoiser.parameters()) + clip_width_extra
    print(f"\npaper U-Net preset: {params / 1e6:.2f} M parameters (MDM: 23.47 M)")
    assert abs(params / 23.47e6 - 1) < 0.05
