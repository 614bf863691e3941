"""Paper presets compose into the configuration they name (no training: Hydra's compose API)."""

from __future__ import annotations

import pytest
from hydra import compose, initialize_config_dir

from motiondiff.cli.common import REPO_DIR, register_resolvers

register_resolvers()


@pytest.mark.parametrize(
    ("preset", "backbone", "input_token"),
    [("mdm_humanml3d", "trans_enc", None), ("mdm_humanml3d_tab1_trans_dec", "trans_dec", False),
     ("mdm_humanml3d_tab1_trans_dec_token", "trans_dec", True), ("mdm_humanml3d_tab1_gru", "gru", None),
     ("mdm_humanml3d_tab1_unet", "unet", None)],
)  # fmt: skip
def test_table1_presets(preset, backbone, input_token):
    with initialize_config_dir(config_dir=str(REPO_DIR / "conf"), version_base="1.3"):
        cfg = compose("train", overrides=[f"experiment={preset}"])
    assert cfg.backbone.name == backbone
    assert cfg.backbone.get("input_token") == input_token
    assert cfg.dataset.name == "humanml3d" and cfg.model.name == "paper" and cfg.text_encoder.name == "clip"
    assert cfg.trainer.max_steps == 500_000 and cfg.batch_size == 64 and cfg.optim.lr == 1e-4
