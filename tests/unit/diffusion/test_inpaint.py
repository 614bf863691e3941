"""In-painting keeps the known part exactly and lets the model generate the rest (overwrite and RePaint modes)."""

from __future__ import annotations

import pytest
import torch
from fixtures.tiny_models import tiny_datamodule, tiny_module

from motiondiff.diffusion.samplers import ddim_sample, ddpm_sample
from motiondiff.edit.inpaint import inpaint


@pytest.fixture(scope="module")
def module():
    return tiny_module(tiny_datamodule()).eval()


@pytest.mark.parametrize("mode", ["overwrite", "repaint"])
@pytest.mark.parametrize("sampler", ["ddim", "ddpm", "dpmpp"])
def test_known_part_is_kept_and_the_rest_generated(module, mode, sampler):
    b, n, d = 2, 30, module.hparams.feature_dim
    known = torch.randn(b, n, d, generator=torch.Generator().manual_seed(1))
    keep = torch.zeros(b, n, 1, dtype=torch.bool)
    keep[:, :8] = keep[:, -8:] = True
    out = inpaint(module, None, known, keep, torch.full((b,), n), mode=mode, sampler=sampler, steps=5,
                  generator=torch.Generator().manual_seed(0))  # fmt: skip
    assert torch.equal(out[:, :8], known[:, :8]) and torch.equal(out[:, -8:], known[:, -8:])
    assert (out[:, 8:-8] - known[:, 8:-8]).abs().mean() > 0.1  # the middle is the model's, not the input


def test_modes_differ_and_overwrite_steers_the_middle(module):
    """The two modes are different algorithms: same noise, same model, different middles."""
    b, n, d = 1, 30, module.hparams.feature_dim
    known = torch.randn(b, n, d, generator=torch.Generator().manual_seed(1))
    keep = torch.zeros(b, n, d, dtype=torch.bool)
    keep[..., : d // 2] = True  # a body-part style mask over feature dims
    lengths = torch.full((b,), n)
    outs = {}
    for m in ("overwrite", "repaint"):
        outs[m] = inpaint(module, None, known, keep, lengths, mode=m, sampler="ddim", steps=5,
                          generator=torch.Generator().manual_seed(0))  # fmt: skip
    assert torch.equal(outs["overwrite"][keep], known[keep]) and torch.equal(outs["repaint"][keep], known[keep])
    assert not torch.allclose(outs["overwrite"][~keep], outs["repaint"][~keep])


def test_hooks_receive_original_step_indices():
    """x_t hooks see the noise level of the x they get: kept[i-1] and finally -1 (clean)."""
    from motiondiff.diffusion.process import GaussianDiffusion

    diffusion = GaussianDiffusion.create(num_steps=100)
    seen = {"ddim": [], "ddpm": []}
    for name, fn in (("ddim", ddim_sample), ("ddpm", ddpm_sample)):

        def hook(x, t, name=name):
            seen[name].append(t)
            return x

        fn(diffusion, lambda x, t: torch.zeros_like(x), (1, 4, 3), steps=4, xt_hook=hook,
           generator=torch.Generator().manual_seed(0))  # fmt: skip
    assert seen["ddim"] == seen["ddpm"] == [66, 33, 0, -1]


def test_bad_mode_is_named(module):
    with pytest.raises(ValueError, match="overwrite, repaint"):
        inpaint(module, None, torch.zeros(1, 4, module.hparams.feature_dim), torch.ones(1, 4, 1, dtype=torch.bool),
                torch.tensor([4]), mode="paint")  # fmt: skip


def test_renoise_step_is_q_of_x_t_given_x_prev():
    """RePaint's jump back: x_t ~ N(√(ᾱ_t/ᾱ_prev) x_prev, (1 − ᾱ_t/ᾱ_prev) I), checked on 200k draws."""
    from motiondiff.diffusion.samplers import renoise_step

    x_prev = torch.full((200_000,), 0.7, dtype=torch.float64)
    a_t, a_prev = 0.3, 0.8
    x_t = renoise_step(x_prev, a_t, a_prev, torch.Generator().manual_seed(0))
    assert abs(x_t.mean().item() - (a_t / a_prev) ** 0.5 * 0.7) < 0.005
    assert abs(x_t.var().item() - (1 - a_t / a_prev)) < 0.005


@pytest.mark.parametrize("sampler", ["ddim", "ddpm"])
def test_resampling_repeats_each_step_but_the_last(sampler):
    """resample=U: U model calls and U hook calls per step except the final clean one; U=1 is the plain sampler."""
    from motiondiff.diffusion.process import GaussianDiffusion

    diffusion = GaussianDiffusion.create(num_steps=100)
    fn = {"ddim": ddim_sample, "ddpm": ddpm_sample}[sampler]
    calls, hooks = [], []

    def model(x, t):
        calls.append(int(t[0]))
        return torch.zeros_like(x)

    def hook(x, t):
        hooks.append(t)
        return x

    gen = torch.Generator().manual_seed(0)
    fn(diffusion, model, (1, 4, 3), steps=4, resample=3, xt_hook=hook, generator=gen)
    assert calls == [99] * 3 + [66] * 3 + [33] * 3 + [0]
    assert hooks == [66] * 3 + [33] * 3 + [0] * 3 + [-1]
    plain = fn(diffusion, model, (1, 4, 3), steps=4, generator=torch.Generator().manual_seed(0))
    again = fn(diffusion, model, (1, 4, 3), steps=4, resample=1, generator=torch.Generator().manual_seed(0))
    assert torch.equal(plain, again)
    with pytest.raises(ValueError, match="resample"):
        fn(diffusion, model, (1, 4, 3), steps=4, resample=0)


@pytest.mark.parametrize("mode", ["overwrite", "repaint"])
def test_resampled_inpainting_keeps_the_known_part(module, mode):
    b, n, d = 1, 20, module.hparams.feature_dim
    known = torch.randn(b, n, d, generator=torch.Generator().manual_seed(2))
    keep = torch.zeros(b, n, 1, dtype=torch.bool)
    keep[:, :5] = keep[:, -5:] = True
    out = inpaint(module, None, known, keep, torch.full((b,), n), mode=mode, sampler="ddim", steps=4, resample=3,
                  generator=torch.Generator().manual_seed(0))  # fmt: skip
    assert torch.equal(out[:, :5], known[:, :5]) and torch.equal(out[:, -5:], known[:, -5:])


def test_sampling_options_name_the_bad_value(module):
    from motiondiff.edit.inpaint import SamplingOptions

    with pytest.raises(ValueError, match="unknown sampling option.*resample"):
        SamplingOptions.from_kwargs({"resampel": 2})
    for bad, match in (({"sampler": "euler"}, "ddim, ddpm"), ({"steps": 0}, "between 1"), ({"resample": 0}, ">= 1"),
                       ({"guidance": -1.0}, "guidance must be >= 0"), ({"hold_from": 0.0}, r"hold_from .* \(0, 1\]"),
                       ({"hold_from": 1.5}, r"hold_from .* \(0, 1\]"),
                       ({"reconstruction": -1.0}, "reconstruction .* >= 0"),
                       ({"reconstruction": "strong"}, "reconstruction .* >= 0")):  # fmt: skip
        with pytest.raises(ValueError, match=match):
            SamplingOptions(**bad).resolved(module, conditioned=True)
    assert SamplingOptions(guidance=3.0).resolved(module, conditioned=False).guidance is None
    assert SamplingOptions().resolved(module, conditioned=True).guidance == module.default_guidance


def test_hooks_hold_the_known_part_only_below_their_noise_level():
    """hold_from < 1: the hooks leave the steps at t >= below alone and hold the known part from there down."""
    from motiondiff.diffusion.guidance import overwrite_known
    from motiondiff.diffusion.process import GaussianDiffusion
    from motiondiff.edit.inpaint import renoise_known

    known, x = torch.ones(1, 4, 3), torch.zeros(1, 4, 3)
    keep = torch.zeros(1, 4, 3, dtype=torch.bool)
    keep[:, :2] = True
    hook = overwrite_known(known, keep, below=50)
    assert torch.equal(hook(x, 50), x) and torch.equal(hook(x, 99), x)
    assert torch.equal(hook(x, 49), torch.where(keep, known, x))
    assert torch.equal(overwrite_known(known, keep)(x, 99), torch.where(keep, known, x))  # no bound: every step
    renoise = renoise_known(GaussianDiffusion.create(num_steps=100), known, keep, torch.Generator().manual_seed(0), 50)
    assert torch.equal(renoise(x, 50), x)
    held = renoise(x, 10)
    assert torch.equal(held[~keep], x[~keep]) and not torch.equal(held[keep], x[keep])
    assert torch.equal(renoise(x, -1), torch.where(keep, known, x))  # the clean result is always the input's


def _edit_runner(module, mode: str, keep: torch.Tensor, seed: int, steps: int):
    """(known, run): random known features shaped like ``keep`` and ``run(**options)`` in-painting them, same noise."""
    b, n = keep.shape[:2]
    known = torch.randn(b, n, module.hparams.feature_dim, generator=torch.Generator().manual_seed(seed))

    def run(**kw):
        return inpaint(module, None, known, keep, torch.full((b,), n), mode=mode, sampler="ddim", steps=steps,
                       generator=torch.Generator().manual_seed(0), **kw)  # fmt: skip

    return known, run


@pytest.mark.parametrize("mode", ["overwrite", "repaint"])
def test_hold_from_keeps_the_known_part_and_changes_only_the_generated_path(module, mode):
    """Held over part of the chain, the result still keeps the known part exactly; hold_from=1 is the default path,
    and a later hold gives a different generated part (the first steps ran free)."""
    d = module.hparams.feature_dim
    keep = torch.zeros(1, 20, d, dtype=torch.bool)
    keep[..., : d // 2] = True
    known, run = _edit_runner(module, mode, keep, seed=3, steps=10)
    default, full, late = run(), run(hold_from=1.0), run(hold_from=0.3)
    assert torch.equal(default, full)
    assert torch.equal(late[keep], known[keep])
    assert not torch.allclose(late[~keep], full[~keep])
    with pytest.raises(ValueError, match="hold_from"):
        run(hold_from=0.0)


def test_reconstruction_guidance_is_ho_et_al_formula():
    """x̃0 = x̂0 − (w √ᾱ_t / 2) ∇_{x_t} ‖keep ⊙ (x_known − x̂0)‖², checked on x̂0 = c · x_t where the gradient is
    −2c keep ⊙ (x_known − c x_t); run inside inference mode as the samplers do; steps at t >= below untouched."""
    from motiondiff.diffusion.guidance import reconstruction_guidance

    gen = torch.Generator().manual_seed(0)
    x, known = torch.randn(2, 6, 4, generator=gen), torch.randn(2, 6, 4, generator=gen)
    keep = torch.zeros(2, 6, 4, dtype=torch.bool)
    keep[:, :2] = True
    c, w, alpha_bar = 0.7, 3.0, 0.64
    guide = reconstruction_guidance(known, keep, w, below=500)
    with torch.inference_mode():
        out = guide(lambda xt: c * xt, x, alpha_bar, 100)
        above = guide(lambda xt: c * xt, x, alpha_bar, 500)
    expected = c * x + w * alpha_bar**0.5 * c * keep * (known - c * x)
    torch.testing.assert_close(out, expected)
    torch.testing.assert_close(above, c * x)
    assert not out.requires_grad


def test_samplers_give_the_guide_each_steps_alpha_bar():
    """The guide sees ᾱ of the noise level it guides (the original index, also on the respaced DDPM chain)."""
    from motiondiff.diffusion.process import GaussianDiffusion

    diffusion = GaussianDiffusion.create(num_steps=100)
    for fn in (ddim_sample, ddpm_sample):
        seen = []

        def guide(predict, x, alpha_bar, t, seen=seen):
            seen.append((t, alpha_bar))
            return predict(x)

        fn(diffusion, lambda x, t: torch.zeros_like(x), (1, 4, 3), steps=4, x0_guide=guide,
           generator=torch.Generator().manual_seed(0))  # fmt: skip
        assert [t for t, _ in seen] == [99, 66, 33, 0]
        for t, alpha_bar in seen:
            assert alpha_bar == pytest.approx(float(diffusion.alphas_cumprod[t]), rel=1e-6)


@pytest.mark.parametrize("mode", ["overwrite", "repaint"])
def test_reconstruction_keeps_the_known_part_and_moves_the_generated_one(module, mode):
    """With reconstruction guidance the known part is still exact; 0 is the plain path; a weight changes the rest."""
    keep = torch.zeros(2, 20, 1, dtype=torch.bool)
    keep[:, :5] = keep[:, -5:] = True
    known, run = _edit_runner(module, mode, keep, seed=4, steps=6)
    plain, zero, guided = run(), run(reconstruction=0.0), run(reconstruction=5.0)
    assert torch.equal(plain, zero)
    assert torch.equal(guided[:, :5], known[:, :5]) and torch.equal(guided[:, -5:], known[:, -5:])
    assert not torch.allclose(guided[:, 5:-5], plain[:, 5:-5])
    with pytest.raises(ValueError, match="reconstruction"):
        run(reconstruction=-1.0)
