"""Editing through the one generation chain: `generate_features` with known frames samples the padded batch that
in-painting samples, in the order given (edits are not sorted by length), and returns the input's own numbers where
they are kept."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from fixtures.tiny_models import tiny_datamodule, tiny_module

from motiondiff.lit.generation import NonFiniteOutput, generate_features
from motiondiff.lit.inpainting import inpaint


@pytest.fixture(scope="module")
def module():
    return tiny_module(tiny_datamodule(max_frames=24), ["condition=none", "model.dropout=0.0"]).eval()


def _items(module, lengths):
    g = np.random.default_rng(0)
    d = module.representation.dim
    known = [g.normal(size=(n, d)).astype(np.float32) for n in lengths]
    keep = [np.zeros((n, d), dtype=bool) for n in lengths]
    for k in keep:
        k[:4] = True  # a kept prefix
        k[:, : d // 3] = True  # and kept dims over every frame
    return known, keep


@pytest.mark.parametrize("mode", ["overwrite", "repaint"])
def test_known_frames_sample_the_inpainting_batch_in_the_given_order(module, mode):
    lengths = [12, 20, 16]  # not sorted: edits keep their order, so a seed draws the noise it drew before
    known, keep = _items(module, lengths)
    options = {"mode": mode, "sampler": "ddim", "steps": 3}
    out = generate_features(module, [None] * 3, torch.tensor(lengths), generator=torch.Generator().manual_seed(0),
                            known=known, keep=keep, **options)  # fmt: skip
    padded = torch.zeros(3, 20, module.representation.dim)
    mask = torch.zeros(3, 20, module.representation.dim, dtype=torch.bool)
    for i, n in enumerate(lengths):
        padded[i, :n], mask[i, :n] = torch.from_numpy(known[i]), torch.from_numpy(keep[i])
    with torch.inference_mode():
        direct = inpaint(module, None, module.normalise(padded), mask, torch.tensor(lengths),
                         generator=torch.Generator().manual_seed(0), **options)  # fmt: skip
    direct = module.denormalise(direct).numpy()
    for i, n in enumerate(lengths):
        assert out[i].shape == known[i].shape
        np.testing.assert_array_equal(out[i], np.where(keep[i], known[i], direct[i, :n]))
        np.testing.assert_array_equal(out[i][keep[i]], known[i][keep[i]])  # the input's own numbers, exactly
        assert np.abs(out[i][~keep[i]] - known[i][~keep[i]]).mean() > 0.1  # the rest is generated


def test_known_frames_need_one_mask_per_motion_and_a_nan_edit_is_one_error(module, monkeypatch):
    known, keep = _items(module, [8, 8])
    with pytest.raises(ValueError, match="one known motion and one keep mask per length"):
        generate_features(module, [None] * 2, torch.tensor([8, 8]), known=known, keep=keep[:1], steps=2)
    monkeypatch.setattr(module, "sample", lambda cond, lengths, **kwargs: torch.full((2, 8, known[0].shape[1]), np.nan))
    with pytest.raises(NonFiniteOutput, match="the edited motion holds"):
        generate_features(module, [None] * 2, torch.tensor([8, 8]), known=known, keep=keep, what="the edited motion",
                          steps=2)  # fmt: skip


def test_many_edits_run_in_batches_of_the_given_order(module):
    known, keep = _items(module, [12, 20, 16])

    def run(count, batch_size):
        return generate_features(module, [None] * count, torch.tensor([len(k) for k in known[:count]]), batch_size,
                                 torch.Generator().manual_seed(3), known=known[:count], keep=keep[:count], steps=2)  # fmt: skip

    whole, batched = run(2, 2), run(3, 2)  # the first batch of three is the two alone, the third a batch of its own
    assert [len(f) for f in batched] == [12, 20, 16]
    for a, b in zip(whole, batched[:2], strict=True):
        np.testing.assert_array_equal(a, b)
