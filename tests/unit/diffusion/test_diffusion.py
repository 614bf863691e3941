"""Diffusion math: schedules, x0/ε/v conversions, loss, DDPM/DDIM samplers, respacing and classifier-free guidance."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from torch import nn

from motiondiff.diffusion import (
    GaussianDiffusion,
    classifier_free_guidance,
    ddim_coefficients,
    ddim_sample,
    ddpm_sample,
    guided_model_fn,
    make_betas,
    masked_mean_per_sample,
    overwrite_known,
    select_timesteps,
)

B, N, D = 4, 7, 3


def _gen(seed: int) -> torch.Generator:
    return torch.Generator().manual_seed(seed)


def _maxdiff(a: torch.Tensor, b: torch.Tensor) -> float:
    return float((a - b).abs().max())


def _data(dtype: torch.dtype, T: int = 1000, seed: int = 0):
    g = _gen(seed)
    x0 = torch.randn(64, N, D, generator=g, dtype=dtype)
    eps = torch.randn(64, N, D, generator=g, dtype=dtype)
    t = torch.cat([torch.tensor([0, T - 1]), torch.randint(0, T, (62,), generator=g)])
    return x0, eps, t


# ---- schedules ---------------------------------------------------------------------------------------------------
def test_cosine_matches_closed_form():
    T, s = 1000, 0.008
    betas = make_betas("cosine", T)
    assert betas.dtype == torch.float64 and betas.shape == (T,)
    assert float(betas.max()) <= 0.999 and float(betas[-1]) == pytest.approx(0.999)
    f = np.cos((np.arange(0, T + 1) / T + s) / (1 + s) * np.pi / 2) ** 2
    expected = f[1:] / f[0]
    ab = np.cumprod(1 - betas.numpy())
    np.testing.assert_allclose(ab[:-1], expected[:-1], rtol=1e-10, atol=1e-15)  # the last step is clipped


def test_linear_and_scaled_linear_endpoints():
    lin = make_betas("linear", 1000)
    assert float(lin[0]) == pytest.approx(1e-4) and float(lin[-1]) == pytest.approx(0.02)
    lin100 = make_betas("linear", 100)
    assert float(lin100[0]) == pytest.approx(1e-3) and float(lin100[-1]) == pytest.approx(0.2)
    custom = make_betas("linear", 10, beta_start=0.1, beta_end=0.5)
    assert float(custom[0]) == pytest.approx(0.1) and float(custom[-1]) == pytest.approx(0.5)
    sl = make_betas("scaled_linear", 1000)
    assert float(sl[0]) == pytest.approx(8.5e-4) and float(sl[-1]) == pytest.approx(0.012)
    np.testing.assert_allclose(np.sqrt(sl.numpy()), np.linspace(np.sqrt(8.5e-4), np.sqrt(0.012), 1000), rtol=1e-12)


def test_bad_names_raise():
    with pytest.raises(ValueError, match="cosine"):
        make_betas("quadratic", 10)
    with pytest.raises(ValueError, match="x0"):
        GaussianDiffusion(make_betas("linear", 100), prediction="score")
    with pytest.raises(ValueError, match="snr_v"):
        GaussianDiffusion(make_betas("linear", 100), weighting="p2")
    with pytest.raises(ValueError, match="beta_end"):
        make_betas("linear", 10)  # 0.02 · 1000/10 = 2 is not a probability


# ---- process -----------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("schedule", ["cosine", "linear"])
def test_q_sample_matches_numpy(schedule):
    diff = GaussianDiffusion.create(schedule, 1000)
    x0, eps, t = _data(torch.float64)
    ab = np.cumprod(1 - make_betas(schedule, 1000).numpy())[t.numpy()][:, None, None]
    expected = np.sqrt(ab) * x0.numpy() + np.sqrt(1 - ab) * eps.numpy()
    np.testing.assert_allclose(diff.q_sample(x0, t, eps).numpy(), expected, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("schedule", ["cosine", "linear"])
def test_conversions_invert_float64(schedule):
    diff = GaussianDiffusion.create(schedule, 1000)
    x0, eps, t = _data(torch.float64)
    x_t = diff.q_sample(x0, t, eps)
    v = diff.v_from_x0_eps(x0, eps, t)
    assert _maxdiff(diff.x0_from_eps(eps, x_t, t), x0) < 1e-10 and _maxdiff(diff.eps_from_x0(x0, x_t, t), eps) < 1e-10
    assert _maxdiff(diff.x0_from_v(v, x_t, t), x0) < 1e-10 and _maxdiff(diff.eps_from_v(v, x_t, t), eps) < 1e-10


@pytest.mark.parametrize("schedule", ["cosine", "linear"])
def test_conversions_float32(schedule):
    """v conversions are rotations (≤ 1e-5 everywhere); x0 ↔ ε divide by √ᾱ or √(1−ᾱ), so their float32 error grows
    as 1e-7/√ᾱ_t (large t) or 1e-7/√(1−ᾱ_t) (small t): checked against that bound."""
    diff = GaussianDiffusion.create(schedule, 1000)
    x0, eps, t = _data(torch.float32)
    x_t = diff.q_sample(x0, t, eps)
    v = diff.v_from_x0_eps(x0, eps, t)
    assert _maxdiff(diff.x0_from_v(v, x_t, t), x0) < 1e-5
    assert _maxdiff(diff.eps_from_v(v, x_t, t), eps) < 1e-5
    a = diff.sqrt_alphas_cumprod[t].float()[:, None, None]
    b = diff.sqrt_one_minus_alphas_cumprod[t].float()[:, None, None]
    assert bool(((diff.x0_from_eps(eps, x_t, t) - x0).abs() <= 1e-5 / a).all())
    assert bool(((diff.eps_from_x0(x0, x_t, t) - eps).abs() <= 1e-5 / b).all())
    mid = (a > 0.1) & (b > 0.1)  # away from both ends: the 1e-5 contract holds for every conversion
    assert float(((diff.x0_from_eps(eps, x_t, t) - x0).abs() * mid).max()) < 1e-5
    assert float(((diff.eps_from_x0(x0, x_t, t) - eps).abs() * mid).max()) < 1e-5


@pytest.mark.parametrize("prediction", ["x0", "eps", "v"])
def test_to_x0_of_target_recovers_x0(prediction):
    diff = GaussianDiffusion.create("cosine", 1000, prediction=prediction)
    x0, eps, t = _data(torch.float64)
    x_t = diff.q_sample(x0, t, eps)
    target = diff.target(x0, eps, t)
    assert _maxdiff(diff.to_x0(target, x_t, t), x0) < 1e-10
    assert _maxdiff(diff.to_eps(target, x_t, t), eps) < 1e-10


def test_loss_weight():
    t = torch.tensor([0, 10, 500, 999])
    v = GaussianDiffusion.create("cosine", 1000, prediction="v")
    assert v.weighting == "snr_v"
    torch.testing.assert_close(v.loss_weight(t, torch.float64), v.alphas_cumprod[t])
    for pred in ("x0", "eps"):
        assert bool((GaussianDiffusion.create("cosine", 1000, prediction=pred).loss_weight(t) == 1).all())
    m = GaussianDiffusion.create("cosine", 1000, prediction="eps", weighting="min_snr", min_snr_gamma=5.0)
    snr = m.snr[t]
    torch.testing.assert_close(m.loss_weight(t, torch.float64), snr.clamp_max(5.0) / snr)


def test_masked_loss_ignores_padding_and_matches_hand_value():
    diff = GaussianDiffusion.create("cosine", 1000, prediction="x0")
    x0 = torch.zeros(2, 3, 2)
    out = torch.tensor([[[1.0, 1.0], [2.0, 0.0], [9.0, 9.0]], [[1.0, 3.0], [5.0, 5.0], [7.0, 7.0]]])
    mask = torch.tensor([[True, True, False], [True, False, False]])
    t = torch.tensor([3, 800])
    # sample 0: (1 + 1 + 4 + 0)/4 = 1.5; sample 1: (1 + 9)/2 = 5; batch mean 3.25
    assert float(diff.loss(out, x0, torch.randn_like(x0), t, mask)) == pytest.approx(3.25)
    padded = out.clone()
    padded[~mask] = 1e6
    assert float(diff.loss(padded, x0, torch.randn_like(x0), t, mask)) == pytest.approx(3.25)
    assert float(diff.loss(out, x0, x0, t)) == pytest.approx(out.pow(2).mean().item())
    assert masked_mean_per_sample(torch.ones(1, 3, 2), torch.zeros(1, 3, dtype=torch.bool)).item() == 0.0
    vdiff = GaussianDiffusion.create("cosine", 1000, prediction="v")
    per = vdiff.loss_per_sample(out, x0, torch.zeros_like(x0), t, mask)  # target v = 0 here
    torch.testing.assert_close(per, vdiff.alphas_cumprod[t].float() * torch.tensor([1.5, 5.0]))


# ---- samplers ----------------------------------------------------------------------------------------------------
def test_ddim_eta1_full_steps_equals_ddpm_posterior():
    diff = GaussianDiffusion.create("cosine", 1000)
    x0, eps, _ = _data(torch.float64)
    ab = diff.alphas_cumprod.tolist()
    for step in (1, 5, 250, 700, 999):
        t = torch.full((64,), step)
        x_t = diff.q_sample(x0, t, eps)
        x0_hat = 0.5 * x0 + 0.1  # any fixed "model output"
        c_x0, c_eps, sigma = ddim_coefficients(ab[step], ab[step - 1], eta=1.0)
        ddim_mean = c_x0 * x0_hat + c_eps * diff.eps_from_x0(x0_hat, x_t, t)
        mean, var, _ = diff.q_posterior(x0_hat, x_t, t)
        assert _maxdiff(ddim_mean, mean) < 1e-5
        assert sigma**2 == pytest.approx(float(var[0]), rel=1e-9)
    t0 = torch.zeros(64, dtype=torch.long)  # the last step: the posterior is a point mass at x̂0
    mean, var, _ = diff.q_posterior(x0, diff.q_sample(x0, t0, eps), t0)
    assert _maxdiff(mean, x0) < 1e-12 and float(var.abs().max()) == 0.0


def test_select_timesteps_and_respacing():
    assert select_timesteps(10, 4) == [0, 3, 6, 9]
    assert select_timesteps(1000, 1) == [999] and select_timesteps(7) == list(range(7))
    kept = select_timesteps(1000, 50)
    assert kept[0] == 0 and kept[-1] == 999 and len(set(kept)) == 50 and kept == sorted(kept)
    diff = GaussianDiffusion.create("cosine", 1000)
    spaced = diff.respace(kept)
    assert spaced.num_steps == 50
    torch.testing.assert_close(spaced.alphas_cumprod, diff.alphas_cumprod[kept], rtol=1e-12, atol=1e-15)
    with pytest.raises(ValueError, match="steps"):
        select_timesteps(10, 11)


@pytest.mark.parametrize("steps", [2, 5, 10, 20, 50, 1000])
def test_logsnr_spacing_is_distinct_and_even_in_log_snr_where_it_can_be(steps):
    diff = GaussianDiffusion.create("cosine", 1000)
    ab = diff.alphas_cumprod.tolist()
    kept = select_timesteps(1000, steps, "logsnr", ab)
    assert len(set(kept)) == steps and kept == sorted(kept) and kept[0] == 0 and kept[-1] == 999
    lam = 0.5 * torch.log(diff.alphas_cumprod / (1 - diff.alphas_cumprod))
    if steps == 10:  # away from the crowded noisy end, the steps are each nearest to their log-SNR target
        targets = torch.linspace(float(lam[-1]), float(lam[0]), steps, dtype=torch.float64).flip(0)
        for k, target in zip(kept[:6], targets[:6], strict=True):
            assert int(torch.argmin((lam - target).abs())) == k
        assert kept[:6] != select_timesteps(1000, 10)[:6]  # not DDIM's
    with pytest.raises(ValueError, match="logsnr spacing needs the process's 1000 values"):
        select_timesteps(1000, 10, "logsnr")
    with pytest.raises(ValueError, match="unknown timestep spacing 'cubic'"):
        select_timesteps(1000, 10, "cubic", ab)


def test_leading_spacing_is_the_official_mdm_ddim_respacing_and_the_samplers_take_it():
    # improved-diffusion's space_timesteps(1000, "ddim50") (MDM's DDIM): range(0, 1000, 20), never t = 999
    assert select_timesteps(1000, 50, "leading") == list(range(0, 1000, 20))
    assert select_timesteps(10, 5, "leading") == [0, 2, 4, 6, 8] and select_timesteps(10, 1, "leading") == [0]
    with pytest.raises(ValueError, match="divides 1000 .* got 7; the nearest are 5 and 8"):
        select_timesteps(1000, 7, "leading")  # range(0, 1000, 142) has 8 steps: no stride gives exactly 7
    diff = GaussianDiffusion.create("cosine", 100, prediction="eps")
    for sample, extra in ((ddim_sample, {}), (ddpm_sample, {})):
        seen: list[int] = []

        def fn(x, t, seen=seen):
            seen.append(int(t[0]))
            return torch.zeros_like(x)

        sample(diff, fn, (1, 3, 2), steps=10, spacing="leading", generator=_gen(0), **extra)
        assert seen == list(range(90, -1, -10))  # the original step indices, noisiest first
    with pytest.raises(ValueError, match="unknown timestep spacing 'trailing'"):
        ddim_sample(diff, _toy_model, (1, 3, 2), steps=10, spacing="trailing")


def _toy_model(x, t):
    return torch.tanh(0.5 * x) + 1e-3 * t[:, None, None].to(x.dtype)


@pytest.mark.parametrize("sampler", ["ddpm", "ddpm_respaced", "ddim", "ddim_eta"])
def test_sampler_shape_dtype_determinism_and_hook(sampler):
    diff = GaussianDiffusion.create("cosine", 100, prediction="x0")
    fn, extra = {"ddpm": (ddpm_sample, {}), "ddpm_respaced": (ddpm_sample, {"steps": 20})}.get(
        sampler, (ddim_sample, {"steps": 20, "eta": 0.7 if sampler == "ddim_eta" else 0.0})
    )

    def run(**kw):
        return fn(diff, _toy_model, (B, N, D), **extra, **kw)

    seen: list[int] = []
    a = run(x0_hook=lambda x0_hat, t: seen.append(t) or x0_hat, generator=_gen(3), progress=True)
    b = run(generator=_gen(3))
    c = run(generator=_gen(4))
    assert a.shape == (B, N, D) and a.dtype == torch.float32 and bool(torch.isfinite(a).all())
    assert torch.equal(a, b) and not torch.equal(a, c)
    expected = list(range(99, -1, -1)) if sampler == "ddpm" else select_timesteps(100, 20)[::-1]
    assert seen == expected
    d64 = run(noise=torch.randn(B, N, D, dtype=torch.float64), generator=_gen(0))
    assert d64.dtype == torch.float64


def test_ddim_eta1_all_steps_reproduces_ddpm_run():
    """Same generator → same noise draws (x_T, then one per step but the last): DDIM(η=1, S=T) is DDPM, step by step."""
    diff = GaussianDiffusion.create("cosine", 100)
    kw = {"dtype": torch.float64, "x0_hook": lambda x0, t: x0.clamp(-1, 1)}
    ddpm = ddpm_sample(diff, _toy_model, (B, N, D), generator=_gen(7), **kw)
    ddim = ddim_sample(diff, _toy_model, (B, N, D), steps=100, eta=1.0, generator=_gen(7), **kw)
    assert _maxdiff(ddpm, ddim) < 1e-8


def test_ddim_eta0_is_deterministic_given_noise():
    diff = GaussianDiffusion.create("linear", 200, prediction="eps")
    noise = torch.randn(B, N, D)
    a = ddim_sample(diff, _toy_model, (B, N, D), noise=noise, generator=_gen(1))
    b = ddim_sample(diff, _toy_model, (B, N, D), noise=noise, generator=_gen(2))
    assert torch.equal(a, b)


@pytest.mark.parametrize("prediction", ["x0", "eps", "v"])
@pytest.mark.parametrize("steps", [None, 25])
def test_ddpm_with_oracle_converges_to_target(prediction, steps):
    diff = GaussianDiffusion.create("cosine", 100, prediction=prediction)
    target = torch.randn(B, N, D, generator=_gen(5))
    calls: list[int] = []

    def oracle(x_t, t):  # the true x0 (the target), expressed as the diffusion's prediction type
        calls.append(int(t[0]))
        eps = diff.eps_from_x0(target, x_t, t)
        return {"x0": target, "eps": eps, "v": diff.v_from_x0_eps(target, eps, t)}[prediction]

    out = ddpm_sample(diff, oracle, (B, N, D), generator=_gen(0), steps=steps)
    assert _maxdiff(out, target) < 1e-4
    assert calls == select_timesteps(100, steps)[::-1]  # the model sees the ORIGINAL indices


# ---- guidance ----------------------------------------------------------------------------------------------------
class TinyDenoiser(nn.Module):
    """Uses everything: t, cond (float (B, C) or class ids (B,)), mask (masked mean over frames) and drop_cond."""

    def __init__(self, d: int = D, c: int = 5, classes: int = 6, hidden: int = 16) -> None:
        super().__init__()
        self.cond_proj, self.classes = nn.Linear(c, hidden), nn.Embedding(classes, hidden)
        self.inp, self.out = nn.Linear(d, hidden), nn.Linear(2 * hidden, d)

    def forward(self, x, t, cond=None, mask=None, drop_cond=None):
        h = self.inp(x) + torch.sin(t.to(x.dtype))[:, None, None]
        c = 0.0 if cond is None else self.classes(cond) if cond.dtype == torch.long else self.cond_proj(cond)
        if drop_cond is not None and cond is not None:
            c = c * (~drop_cond)[:, None].to(c.dtype)
        m = torch.ones(x.shape[:2], dtype=torch.bool) if mask is None else mask
        pooled = (h * m[..., None]).sum(1) / m.sum(1, keepdim=True).clamp_min(1)
        return self.out(torch.cat([h, (pooled + c)[:, None].expand_as(h)], dim=-1))


@pytest.mark.parametrize("cond_kind", ["float", "long"])
def test_cfg_batched_equals_two_forwards(cond_kind):
    torch.manual_seed(0)
    model = TinyDenoiser().eval()
    x, t = torch.randn(B, N, D), torch.randint(0, 1000, (B,))
    cond = torch.randn(B, 5) if cond_kind == "float" else torch.randint(0, 6, (B,))
    mask = torch.arange(N)[None] < torch.tensor([7, 5, 3, 1])[:, None]
    on, off = torch.zeros(B, dtype=torch.bool), torch.ones(B, dtype=torch.bool)
    with torch.no_grad():
        c = model(x, t, cond=cond, mask=mask, drop_cond=on)
        u = model(x, t, cond=cond, mask=mask, drop_cond=off)
        assert _maxdiff(c, u) > 1e-3 and _maxdiff(c, model(x, t, cond=cond, drop_cond=on)) > 1e-3  # both matter
        for s in (2.5, 7.5):
            got = classifier_free_guidance(model, x, t, cond, s, mask=mask)
            assert _maxdiff(got, u + s * (c - u)) < 1e-5
        assert torch.equal(classifier_free_guidance(model, x, t, cond, 1.0, mask=mask), c)
        assert _maxdiff(classifier_free_guidance(model, x, t, cond, 0.0, mask=mask), u) < 1e-6
        per_sample = classifier_free_guidance(model, x, t, cond, torch.tensor([0.0, 1.0, 2.5, 7.5]), mask=mask)
        assert _maxdiff(per_sample[2], u[2] + 2.5 * (c[2] - u[2])) < 1e-5
        plain = model(x, t, cond=None, mask=mask)
        assert torch.equal(classifier_free_guidance(model, x, t, None, 2.5, mask=mask), plain)
        fn = guided_model_fn(model, cond, 2.5, mask=mask)
        assert _maxdiff(fn(x, t), u + 2.5 * (c - u)) < 1e-5
    with pytest.raises(TypeError, match="drop_cond"):
        classifier_free_guidance(model, x, t, cond, 2.5, drop_cond=on)


def test_editing_with_guidance_in_a_sampler():
    """MDM editing: x0_hook overwrites the kept frames at every step, so the result keeps them exactly; CFG inside."""
    model = TinyDenoiser().eval()
    diff = GaussianDiffusion.create("cosine", 100, prediction="v")
    known, keep = torch.randn(B, N, D), (torch.arange(N) < 2)[None, :, None]
    fn = guided_model_fn(model, torch.randint(0, 6, (B,)), 2.5, mask=torch.ones(B, N, dtype=torch.bool))
    out = ddim_sample(diff, fn, (B, N, D), steps=10, generator=_gen(0), x0_hook=overwrite_known(known, keep))
    assert out.shape == (B, N, D) and bool(torch.isfinite(out).all())
    torch.testing.assert_close(out[:, :2], known[:, :2])
