"""Root-path closure after in-betweening HumanML3D features: the kept end decodes where the input had it."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from hydra import compose, initialize_config_dir

from motiondiff.cli.common import REPO_DIR, register_resolvers
from motiondiff.data.datamodules import PreparedDataModule, embedded_data_root
from motiondiff.data.formats.prepared import load_split
from motiondiff.data.representations import get_representation
from motiondiff.edit import close_root_path, dataset_motions, inbetween, needs_root_closure
from motiondiff.edit.trajectory import gaps
from motiondiff.geometry.skeleton import SMPL22, get_skeleton

register_resolvers()
HML = get_representation("hml263", SMPL22)


@pytest.fixture(scope="module")
def clips():
    """Two real test clips: a straight walk (the input) and a turning walk (a stand-in for a generated middle)."""
    data = load_split(embedded_data_root(), "test")
    ids = [str(i) for i in data.arrays["ids"]]
    walk, turn = (data.arrays["features"][data.feature_slice(ids.index(c))]
                  for c in ("dataset-1_walk_active_001", "dataset-2_walk-turn-right_active_035"))  # fmt: skip
    n = min(len(walk), len(turn))
    return walk[:n].astype(np.float64), turn[:n].astype(np.float64)


def _splice(known, other, generated):
    out = known.copy()
    out[generated] = other[generated]
    return out


def test_gaps_are_runs_of_true():
    assert gaps(np.array([0, 1, 1, 0, 0, 1, 0, 1], dtype=bool)) == [(1, 3), (5, 6), (7, 8)]
    assert gaps(np.zeros(4, dtype=bool)) == []
    assert gaps(np.array([True, False, False, True, True, False])) == [(0, 1), (3, 5)]  # also edit.blend's runs


def test_closure_lands_the_suffix_on_the_input(clips):
    known, other = clips
    n = len(known)
    generated = np.zeros(n, dtype=bool)
    generated[20 : n - 20] = True
    spliced = _splice(known, other, generated)
    target = HML.decode_numpy(known)
    before = np.linalg.norm(HML.decode_numpy(spliced) - target, axis=-1)[n - 20 :].max()
    closed = close_root_path(spliced, known, generated)
    after = np.linalg.norm(HML.decode_numpy(closed) - target, axis=-1)
    assert before > 0.3  # a different middle walks the end somewhere else
    assert after[n - 20 :].max() <= 1e-4 and after[:20].max() == 0.0
    changed = np.abs(closed - spliced) > 0
    assert not changed[~generated].any() and set(np.flatnonzero(changed.any(0))) <= {0, 1, 2}  # root turn + step only
    # the residual is spread evenly: each generated row's turn moves by the same amount
    shift = closed[generated, 0] - spliced[generated, 0]
    assert np.allclose(shift, shift[0])


def test_several_gaps_and_a_gap_at_the_end(clips):
    known, other = clips
    n = len(known)
    generated = np.zeros(n, dtype=bool)
    generated[5:15] = generated[30:40] = generated[n - 10 :] = True
    closed = close_root_path(_splice(known, other, generated), known, generated)
    err = np.linalg.norm(HML.decode_numpy(closed) - HML.decode_numpy(known), axis=-1).max(-1)
    kept = ~generated
    assert err[kept].max() <= 1e-4
    assert np.array_equal(closed[n - 10 :], other[n - 10 :])  # nothing after the last gap to meet: left as generated


def test_only_velocity_roots_need_closure():
    rig = load_split(embedded_data_root(), "test").rig()
    assert needs_root_closure(HML) and needs_root_closure(get_representation("kit251", get_skeleton("kit21")))
    assert not needs_root_closure(get_representation("jp", SMPL22))
    assert not needs_root_closure(get_representation("rp6jr", SMPL22, rig))


@pytest.fixture(scope="module")
def module():
    """An untrained tiny hml263 model: its middles are noise, so the closure has a large residual to remove."""
    from motiondiff.cli.train import build_module

    dm = PreparedDataModule(embedded_data_root(), batch_size=8, max_frames=80)
    dm.setup("fit")
    with initialize_config_dir(config_dir=str(REPO_DIR / "conf"), version_base="1.3"):
        cfg = compose("train", overrides=["model.d_model=32", "model.num_layers=1", "model.num_heads=2",
                                          "model.ff_size=64", "condition=none"])  # fmt: skip
    torch.manual_seed(0)
    return build_module(cfg, dm).eval()


def test_inbetween_closes_the_root_of_a_batch(module):
    motions = dataset_motions(module, "test")[:3]
    common = {"prefix": 0.25, "suffix": 0.25, "num_samples": 2, "steps": 3, "seed": 0}
    closed = inbetween(module, motions, None, **common)
    open_ = inbetween(module, motions, None, close_root=False, **common)
    assert len(closed) == 6 and closed.motion_index == [0, 0, 1, 1, 2, 2] and closed.settings["close_root"]
    for i in range(len(closed)):
        kept = closed.kept_points(i)
        err = np.linalg.norm(closed.joints[i] - closed.input_joints[i], axis=-1)[kept].max()
        err_open = np.linalg.norm(open_.joints[i] - open_.input_joints[i], axis=-1)[kept].max()
        assert err <= 1e-4 < 1e-2 < err_open
        assert np.array_equal(
            closed.features[i][closed.keep[i]], motions[closed.motion_index[i]].features[closed.keep[i]]
        )
