"""The project's noise schedules and samplers (motiondiff.diffusion) against diffusers' schedulers.

    /tmp/depvenv/bin/python bench/dependencies/schedulers.py

Schedules: betas and ᾱ of cosine (diffusers' squaredcos_cap_v2), linear and scaled_linear at T = 1000, and the
forward process (q_sample against add_noise, the v target against get_velocity). Samplers: timesteps and the final
sample of a whole loop from the same x_T, float32 as the project samples, with the same stand-in network: the exact
denoiser of Gaussian data (diffusers with prediction_type="sample"), so the probability-flow ODE's end point is
known in closed form and each deterministic sampler's error against it is measured too. DDIM-50 (η = 0; diffusers'
DDIMScheduler with each of its timestep spacings), DDPM over all 1000 steps and respaced to 50 (same generator: the
noise draws line up), DPM-Solver++(2M) at 7 and 10 steps (the project's log-SNR spacing against diffusers'
use_lu_lambdas, and both on the project's timesteps, which isolates the update rule). Where the two disagree, the
project's update is rerun with diffusers' rule (DDIM's previous step at t − T//S; DPM-Solver's order per step) to
show that rule is the whole difference. Differences are max |a − b| over the sample divided by the sample's standard
deviation. Speed: the same loops with a network that costs nothing (x̂0 = 0.5 x_t), so only the sampler's own work
is timed, at (32, 196, 263), MDM's batch at HumanML3D size. Writes docs/results/dependencies/schedulers.json.
"""

from __future__ import annotations

import sys
from pathlib import Path

import torch

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import import_seconds, install_cost, max_abs, require, speed, write  # noqa: E402

from motiondiff.diffusion import GaussianDiffusion, ddim_sample, ddpm_sample, dpmpp_sample  # noqa: E402
from motiondiff.diffusion.dpm_solver import _step_orders as ORIGINAL_ORDERS  # noqa: E402
from motiondiff.diffusion.samplers import ddim_coefficients, select_timesteps  # noqa: E402
from motiondiff.diffusion.schedules import make_betas  # noqa: E402

diffusers = require("diffusers")
from diffusers import DDIMScheduler, DDPMScheduler, DPMSolverMultistepScheduler  # noqa: E402

T = 1000
SHAPE = (4, 60, 263)
SPEED_SHAPE = (32, 196, 263)


def gaussian_denoiser(proc: GaussianDiffusion, dim: int, seed: int = 0):
    """The exact x̂0 of data x0 ~ N(mu, diag s²): E[x0 | x_t] = mu + a s² (x_t − a mu)/(a² s² + b²), a = √ᾱ_t,
    b = √(1 − ᾱ_t). A stand-in network that is a perfect denoiser, so the probability-flow ODE that DDIM and
    DPM-Solver++ approximate has a closed-form end point (`exact_ode_end`). Same function for both libraries."""
    g = torch.Generator().manual_seed(seed)
    mu, s = 0.5 * torch.randn(dim, generator=g), 0.05 + 1.5 * torch.rand(dim, generator=g)
    alpha_bar = proc.alphas_cumprod

    def net(x: torch.Tensor, t) -> torch.Tensor:
        ab = alpha_bar[int(torch.as_tensor(t).reshape(-1)[0])]
        a, b2 = ab.sqrt(), 1.0 - ab
        out = mu + a * s**2 * (x.double() - a * mu) / (ab * s**2 + b2)
        return out.to(x.dtype)

    def exact_ode_end(x_T: torch.Tensor) -> torch.Tensor:
        """The ODE keeps z = (x_t − a mu)/√(a² s² + b²) fixed, so it ends at mu + s z_T."""
        ab = alpha_bar[-1]
        return (mu + s * (x_T.double() - ab.sqrt() * mu) / (ab * s**2 + 1.0 - ab).sqrt()).float()

    return net, exact_ode_end


def rel(a: torch.Tensor, b: torch.Tensor) -> float:
    return max_abs(a, b) / float(a.double().std())


def error(reference: torch.Tensor, x: torch.Tensor) -> dict:
    """Distance to the exact end point, in units of its standard deviation: the largest and the root-mean-square."""
    scale = float(reference.double().std())
    return {
        "max": max_abs(reference, x) / scale,
        "rms": float((reference.double() - x.double()).pow(2).mean().sqrt()) / scale,
    }


# ---- schedules and the forward process ----------------------------------------------------------------------------
def schedules() -> dict:
    cases = {
        "cosine": ({}, {"beta_schedule": "squaredcos_cap_v2"}),
        "linear": ({}, {"beta_schedule": "linear", "beta_start": 1e-4, "beta_end": 0.02}),
        "scaled_linear (GuidedMotion's 8.5e-4 -> 0.012)": (
            {}, {"beta_schedule": "scaled_linear", "beta_start": 8.5e-4, "beta_end": 0.012}),
    }  # fmt: skip
    out = {}
    for name, (ours_kw, theirs_kw) in cases.items():
        ours = make_betas(name.split(" ")[0], T, **ours_kw)
        theirs = DDPMScheduler(num_train_timesteps=T, **theirs_kw)
        ab_ours, ab_theirs = torch.cumprod(1 - ours, 0), theirs.alphas_cumprod.double()
        out[name] = {
            "betas_max_abs_difference": max_abs(ours, theirs.betas),
            "alphas_cumprod_max_abs_difference": max_abs(ab_ours, ab_theirs),
            "alphas_cumprod_max_relative_difference": float(((ab_ours - ab_theirs).abs() / ab_ours).max()),
            "diffusers_table_dtype": str(theirs.alphas_cumprod.dtype),
        }
    return out


def forward_process() -> dict:
    proc = GaussianDiffusion.create("cosine", T, prediction="v")
    sched = DDPMScheduler(num_train_timesteps=T, beta_schedule="squaredcos_cap_v2")
    g = torch.Generator().manual_seed(1)
    x0, noise = torch.randn(SHAPE, generator=g), torch.randn(SHAPE, generator=g)
    t = torch.tensor([0, 300, 700, 999])
    return {
        "q_sample_vs_add_noise": rel(proc.q_sample(x0, t, noise), sched.add_noise(x0, noise, t)),
        "v_target_vs_get_velocity": rel(proc.target(x0, noise, t), sched.get_velocity(x0, noise, t)),
    }


# ---- samplers -----------------------------------------------------------------------------------------------------
def diffusers_loop(sched, net, x_t: torch.Tensor, generator: torch.Generator | None = None) -> torch.Tensor:
    x = x_t.clone()
    for t in sched.timesteps:
        kw = {"generator": generator} if generator is not None else {}
        x = sched.step(net(x, t), t, x, **kw).prev_sample
    return x


def ddim_with_fixed_stride(proc, net, x_t, steps: int) -> torch.Tensor:
    """The project's DDIM update on its own timesteps, but with ᾱ_prev read at t − T//steps (diffusers' rule)
    instead of at the next timestep of the list: a check that this rule is the whole difference."""
    kept = select_timesteps(T, steps)[::-1]
    alpha_bar = proc.alphas_cumprod.tolist()
    x = x_t.clone()
    for t in kept:
        prev = t - T // steps
        c_x0, c_eps, _ = ddim_coefficients(alpha_bar[t], alpha_bar[prev] if prev >= 0 else 1.0, 0.0)
        tt = torch.full((x.shape[0],), t, dtype=torch.long)
        x0 = proc.to_x0(net(x, tt), x, tt)
        x = c_x0 * x0 + c_eps * proc.eps_from_x0(x0, x, tt)
    return x


def ddim(proc, net, x_t, reference) -> dict:
    ours_steps = select_timesteps(T, 50)[::-1]
    ours = ddim_sample(proc, net, SHAPE, steps=50, noise=x_t)
    out = {"project_first_timesteps": ours_steps[:3], "project_error_vs_exact_ode_end": error(reference, ours)}
    for spacing in ("linspace", "leading", "trailing"):
        sched = DDIMScheduler(num_train_timesteps=T, beta_schedule="squaredcos_cap_v2", prediction_type="sample",
                              clip_sample=False, set_alpha_to_one=True, timestep_spacing=spacing)  # fmt: skip
        sched.set_timesteps(50)
        theirs_steps = sched.timesteps.tolist()
        theirs = diffusers_loop(sched, net, x_t)
        out[spacing] = {
            "timesteps_differing": sum(a != b for a, b in zip(theirs_steps, ours_steps, strict=True)),
            "first_timesteps": theirs_steps[:3],
            "final_sample_relative_difference": rel(ours, theirs),
            "diffusers_error_vs_exact_ode_end": error(reference, theirs),
        }
        if spacing == "linspace":
            out[spacing]["project_update_with_diffusers_stride_rule_vs_diffusers"] = rel(
                theirs, ddim_with_fixed_stride(proc, net, x_t, 50)
            )
    return out


def ddpm(proc, net, x_t) -> dict:
    out = {}
    for steps in (T, 50):
        ours = ddpm_sample(proc, net, SHAPE, steps=steps, noise=x_t, generator=torch.Generator().manual_seed(7))
        row = {}
        for label, kw in (("linspace", {"timestep_spacing": "linspace"}), ("project's timesteps", None)):
            sched = DDPMScheduler(num_train_timesteps=T, beta_schedule="squaredcos_cap_v2", prediction_type="sample",
                                  clip_sample=False, variance_type="fixed_small_log", **(kw or {}))  # fmt: skip
            if kw is None:
                sched.set_timesteps(timesteps=select_timesteps(T, steps)[::-1])
            else:
                sched.set_timesteps(steps)
            theirs = diffusers_loop(sched, net, x_t, torch.Generator().manual_seed(7))
            row[label] = rel(ours, theirs)
        out[f"{steps} steps"] = row
    return out


def diffusers_orders(num: int, order: int) -> list[int]:
    """The order diffusers' DPMSolverMultistepScheduler gives each of ``num`` updates (final_sigmas_type="zero",
    lower_order_final): ramping up with the history, first order for the last, and for solver_order 3 at most second
    for the one before it when num < 15; the update before the last stays second order for solver_order 2."""
    orders = []
    for j in range(num):
        if j == num - 1:
            orders.append(1)
        elif order == 3 and j == num - 2 and num < 15:
            orders.append(min(2, j + 1))
        else:
            orders.append(min(order, j + 1))
    return orders


def dpm_solver(proc, net, x_t, reference) -> dict:
    import motiondiff.diffusion.dpm_solver as dpm

    out = {}
    for steps in (7, 10):
        ours_steps = select_timesteps(T, steps, "logsnr", proc.alphas_cumprod.tolist())[::-1]
        ours = dpmpp_sample(proc, net, SHAPE, steps=steps, order=2, noise=x_t)
        base = {"num_train_timesteps": T, "beta_schedule": "squaredcos_cap_v2", "prediction_type": "sample",
                "algorithm_type": "dpmsolver++", "solver_order": 2, "final_sigmas_type": "zero"}  # fmt: skip
        lu = DPMSolverMultistepScheduler(**base, use_lu_lambdas=True)
        lu.set_timesteps(steps)
        same = DPMSolverMultistepScheduler(**base)
        same.set_timesteps(timesteps=ours_steps)
        theirs_lu, theirs_same = diffusers_loop(lu, net, x_t), diffusers_loop(same, net, x_t)
        own_orders = dpm._step_orders(steps, 2)
        try:  # the project's solver with diffusers' order per update: a check that the orders are the whole difference
            dpm._step_orders = diffusers_orders
            patched = dpmpp_sample(proc, net, SHAPE, steps=steps, order=2, noise=x_t)
        finally:
            dpm._step_orders = ORIGINAL_ORDERS
        out[f"{steps} steps"] = {
            "project_timesteps": ours_steps,
            "diffusers_lu_lambdas_timesteps": lu.timesteps.tolist(),
            "project_orders": own_orders,
            "diffusers_orders": diffusers_orders(steps, 2),
            "final_sample_relative_difference_own_spacings": rel(ours, theirs_lu),
            "final_sample_relative_difference_same_timesteps": rel(ours, theirs_same),
            "project_with_diffusers_orders_vs_diffusers_same_timesteps": rel(theirs_same, patched),
            "project_error_vs_exact_ode_end": error(reference, ours),
            "diffusers_error_vs_exact_ode_end_same_timesteps": error(reference, theirs_same),
            "diffusers_error_vs_exact_ode_end_lu_lambdas": error(reference, theirs_lu),
        }
    return out


def sampler_speed() -> dict:
    proc = GaussianDiffusion.create("cosine", T, prediction="x0")
    x_t = torch.randn(SPEED_SHAPE, generator=torch.Generator().manual_seed(3))

    def free(x, t):
        return 0.5 * x

    def theirs(cls, steps, **kw):
        def run():
            sched = cls(num_train_timesteps=T, beta_schedule="squaredcos_cap_v2", prediction_type="sample", **kw)
            sched.set_timesteps(steps)
            return diffusers_loop(sched, free, x_t)

        return run

    rows = {
        "DDIM-50": (lambda: ddim_sample(proc, free, SPEED_SHAPE, steps=50, noise=x_t),
                    theirs(DDIMScheduler, 50, clip_sample=False, timestep_spacing="linspace")),
        "DPM-Solver++(2M)-7": (lambda: dpmpp_sample(proc, free, SPEED_SHAPE, steps=7, noise=x_t),
                               theirs(DPMSolverMultistepScheduler, 7, use_lu_lambdas=True, final_sigmas_type="zero")),
    }  # fmt: skip
    with torch.inference_mode():
        return {name: speed(ours, lib, repeats=5) for name, (ours, lib) in rows.items()}


def main() -> int:
    proc = GaussianDiffusion.create("cosine", T, prediction="x0")
    net, exact_ode_end = gaussian_denoiser(proc, SHAPE[-1])
    x_t = torch.randn(SHAPE, generator=torch.Generator().manual_seed(5))
    with torch.inference_mode():
        reference = exact_ode_end(x_t)  # where the probability-flow ODE from x_T ends: what DDIM/DPM-Solver approximate
        result = {
            "ddim_1000_error_vs_exact_ode_end": error(reference, ddim_sample(proc, net, SHAPE, steps=T, noise=x_t)),
            "schedules": schedules(),
            "forward_process_relative_difference": forward_process(),
            "ddim_50": ddim(proc, net, x_t, reference),
            "ddpm": ddpm(proc, net, x_t),
            "dpm_solver_pp_2m": dpm_solver(proc, net, x_t, reference),
        }
    result["sampler_speed_free_network"] = {"shape": list(SPEED_SHAPE), **sampler_speed()}
    result["size"] = {"diffusers": install_cost("diffusers"), "diffusers_import_s": import_seconds("diffusers"),
                      "diffusers_schedulers_import_s": import_seconds(
                          "diffusers.schedulers.scheduling_dpmsolver_multistep"),
                      "project_diffusion_import_s": import_seconds("motiondiff.diffusion")}  # fmt: skip
    write("schedulers", result)
    for key, value in result.items():
        print(key, value)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
