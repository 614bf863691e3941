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


PRESETS = sorted(p.stem for p in (REPO_DIR / "conf" / "experiment").glob("*.yaml"))


def _compose(preset: str):
    with initialize_config_dir(config_dir=str(REPO_DIR / "conf"), version_base="1.3"):
        return compose("train", overrides=[f"experiment={preset}"])


@pytest.mark.parametrize("preset", PRESETS)
def test_every_preset_composes_to_a_valid_combination(preset):
    from motiondiff.data.representations import REPRESENTATIONS, ROTATION_REPRESENTATIONS

    cfg = _compose(preset)
    rep = cfg.representation
    assert rep is None or rep in REPRESENTATIONS
    if rep in ROTATION_REPRESENTATIONS:  # rotations exist only where the dataset stores them
        assert cfg.dataset.name in ("humanact12", "uestc", "bandai", "bandai_mini", "bvh")
    assert cfg.diffusion.prediction in ("x0", "eps", "v") and cfg.loss.name in ("simple", "geometric")
    if preset.startswith(("mdm_", "vvmdm_")):  # paper presets: paper-size network, batch 64, lr 1e-4
        assert cfg.model.name == "paper" and cfg.batch_size == 64 and cfg.optim.lr == 1e-4 and not cfg.ema


@pytest.mark.parametrize(
    ("preset", "dataset", "condition", "prediction", "representation", "loss", "steps", "frames"),
    [("mdm_humanact12_tab3", "humanact12", "action", "x0", "rp6jr", (1, 1, 1), 750_000, 60),
     ("mdm_humanact12_tab3_no_foot", "humanact12", "action", "x0", "rp6jr", (1, 1, 0), 750_000, 60),
     ("mdm_humanact12_tab7_velocity_only", "humanact12", "action", "x0", "rp6jr", (0, 1, 0), 750_000, 60),
     ("mdm_uestc_tab4", "uestc", "action", "x0", "rp6jr", (1, 1, 1), 2_000_000, 60),
     ("mdm_humanact12_tab5_unconstrained", "humanact12", "none", "x0", "rp6jr", (1, 1, 1), 750_000, 60),
     ("vvmdm_humanact12_tab1_jp", "humanact12", "none", "v", "jp", (1, 1, 1), 500_000, 64),
     ("vvmdm_humanact12_tab1_rpqjr", "humanact12", "none", "v", "rpqjr", (1, 1, 1), 500_000, 64),
     ("vvmdm_humanact12_tab1_mdm_rp6jr", "humanact12", "none", "x0", "rp6jr", (1, 1, 1), 500_000, 64),
     ("vvmdm_humanact12_tab3_no_geometric", "humanact12", "none", "v", "jp", (0, 0, 0), 500_000, 64),
     ("cpu_twin_vvmdm_tab1_jp", "bandai_mini", "none", "v", "jp", (1, 1, 1), 3500, 80)],
)  # fmt: skip
def test_method_presets(preset, dataset, condition, prediction, representation, loss, steps, frames):
    cfg = _compose(preset)
    assert (cfg.dataset.name, cfg.condition.kind, cfg.diffusion.prediction) == (dataset, condition, prediction)
    assert cfg.representation == representation and cfg.trainer.max_steps == steps
    assert (cfg.loss.lambda_pos, cfg.loss.lambda_vel, cfg.loss.lambda_foot) == loss
    assert cfg.dataset.datamodule.max_frames == frames
    if prediction == "v":
        assert cfg.diffusion.weighting == "snr_v"  # vvMDM's w(t) = SNR/(SNR+1)


@pytest.mark.parametrize(("preset", "steps"), [("mdm_humanml3d_tab6_t10", 10), ("mdm_humanml3d_tab6_t100", 100),
                                               ("mdm_humanml3d_tab6_t500", 500)])  # fmt: skip
def test_diffusion_step_presets(preset, steps):
    cfg = _compose(preset)
    assert cfg.diffusion.steps == steps and cfg.dataset.name == "humanml3d" and cfg.diffusion.prediction == "x0"
