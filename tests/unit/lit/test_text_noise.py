"""condition.text_noise (issue 39): training adds Gaussian noise of the asked expected norm to the caption features
the denoiser sees; validation's loss and sampling see the captions' own features."""

from __future__ import annotations

import torch
from fixtures.tiny_models import tiny_datamodule, tiny_module


def _seen_conditions(module, batch, perturb: bool) -> torch.Tensor:
    seen = []
    forward = module.denoiser.forward

    def spy(*args, **kwargs):
        seen.append(kwargs["cond"].detach().clone())
        return forward(*args, **kwargs)

    module.denoiser.forward = spy
    module._loss(batch, 0.0, perturb=perturb)
    module.denoiser.forward = forward
    return seen[0]


def test_training_noise_has_the_asked_norm_and_validation_sees_none():
    dm = tiny_datamodule()
    module = tiny_module(dm, ["condition=text", "condition.text_noise=0.3"])
    batch = next(iter(dm.train_dataloader()))
    texts = sorted(set(batch["text"]))
    module.set_text_table(torch.randn(len(texts), 384), {t: i for i, t in enumerate(texts)})
    clean = module.batch_condition(batch)
    assert torch.equal(_seen_conditions(module, batch, perturb=False), clean)
    noise = torch.cat([_seen_conditions(module, batch, perturb=True) - clean for _ in range(20)])
    assert abs(noise.norm(dim=1).mean().item() - 0.3) < 0.03
