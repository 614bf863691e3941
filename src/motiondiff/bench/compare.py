"""The side-by-side comparison: the same workloads on this project's code and, given a local checkout of the official
MDM code (`bench/run.py --official <path>`), on that code in the same run, and its table. Training and forward rows
show the achieved GFLOP/s (counted FLOPs over the median) and their share of this run's matmul peak (the suite's
large GEMM in the same dtype). Without a checkout the table has this project's column only.

Workloads: training steps at batch 64 and 16, the batch-1 forward plain and with classifier-free guidance, and one
motion from random caption features with guided DDIM-50 and with DDPM-1000 (the official sample.py's default; timed
over its first ``DDPM_TIMED`` steps and scaled). Both sides use randomly initialised networks of the same preset.
"""

from __future__ import annotations

from motiondiff.bench import official, workloads
from motiondiff.bench.flops import count_flops
from motiondiff.bench.official_code import OfficialCode
from motiondiff.bench.timing import format_seconds

DDPM_TIMED = 20
TWO_FORWARDS = "official: conditional and unconditional forward one after the other; motiondiff: one doubled batch"


def _official_row(s, label: str, key: str, run, flops: int | None = None, scale: float = 1.0, note: str = "") -> None:
    """Time an official workload as row ``official MDM: <label>``, key ``official_<key>`` (with its GFLOP/s)."""
    note = f"{flops / 1e9:.1f} GFLOP" if flops is not None else note
    row = s.time(f"official MDM: {label}", run, key=f"official_{key}", scale=scale, **({"note": note} if note else {}))
    if flops is not None:
        row["flops_per_s"] = flops / row["median_s"]
        row["detail"] += f"; {row['flops_per_s'] / 1e9:.1f} GFLOP/s"


def run_comparison(s, quick: bool, code: OfficialCode | None, bf16_options: list[bool]) -> list[dict]:
    """Time the comparison's rows the suite has not timed already (this project's guided forward and sampling from
    caption features; every official row) and return the pairs, each {workload, motiondiff_key, official_key, dtype,
    note}; keys name rows in ``s.keys``, dtype (training and forward rows) picks the matmul peak."""
    preset, size, frames = (workloads.TINY, "tiny", 20) if quick else ("paper", "paper", 196)
    pairs = []

    def pair(workload: str, key: str, dtype: str | None = None, note: str = "") -> None:
        pairs.append({"workload": workload, "motiondiff_key": key, "official_key": f"official_{key}" if code else None,
                      "dtype": dtype, "note": note})  # fmt: skip

    for batch in (64, 16):  # this project's rows: the suite's training steps
        for bf16 in bf16_options:
            key, suffix = f"train_step_paper_bs{batch}{'_bf16' if bf16 else ''}_s", ", bf16 autocast" if bf16 else ""
            if code:
                step = official.train_step(code, preset, 4 if quick else batch, frames, bf16=bf16)
                name = f"train step, {size} preset, batch {batch}, {frames} frames{suffix}"
                _official_row(s, name, key, step, flops=count_flops(step))
            pair(f"train step, batch {batch}, {frames} frames{suffix}", key, "bfloat16" if bf16 else "float32")
    for bf16 in bf16_options:  # this project's row: the suite's batch-1 forward
        key, suffix = f"forward_paper_bs1{'_bf16' if bf16 else ''}_s", " bf16" if bf16 else ""
        if code:
            run, flops = (
                official.forward(code, preset, 1, frames, bf16=bf16),
                official.forward_flops(code, preset, 1, frames),
            )
            _official_row(s, f"denoiser forward, {size} preset, batch 1{suffix}", key, run, flops=flops)
        pair(f"denoiser forward, batch 1{suffix}", key, "bfloat16" if bf16 else "float32")

    label = f"guided forward, batch 1, guidance {workloads.GUIDANCE}"
    row = s.time(
        f"{label}, {size} preset", workloads.guided_forward(preset, 1, frames), key="guided_forward_paper_bs1_s"
    )
    row["flops_per_s"] = workloads.forward_flops(preset, 1, frames, guided=True) / row["median_s"]
    row["detail"] += f"; {row['flops_per_s'] / 1e9:.1f} GFLOP/s"
    if code:
        run, flops = (
            official.forward(code, preset, 1, frames, guided=True),
            official.forward_flops(code, preset, 1, frames, True),
        )
        _official_row(s, f"{label}, {size} preset", "guided_forward_paper_bs1_s", run, flops=flops)
    pair(label, "guided_forward_paper_bs1_s", "float32", TWO_FORWARDS)

    for sampler, total, timed in (("ddim", 50, None), ("ddpm", 1000, 2 if quick else DDPM_TIMED)):
        key = f"sample_features_{sampler}{total}_guided_s"
        label = f"one motion from caption features, {sampler.upper()}-{total}, guidance {workloads.GUIDANCE}"
        run, total, done = workloads.feature_sampling(preset, frames, sampler, None, timed_steps=timed)
        note = f"timed over {done} of {total} steps, scaled" if done < total else f"{total} steps"
        s.time(f"{label}, {size} preset (random weights)", run, key=key, scale=total / done, note=note)
        if code:
            run, total, done = official.sampling(code, preset, frames, sampler, timed_steps=timed)
            loop = "ddim_sample_loop on its 'ddim50' respacing" if sampler == "ddim" else "p_sample_loop, its default"
            _official_row(s, f"{label}, {size} preset ({loop})", key, run, scale=total / done, note=note)
        pair(label, key, note=note)
    for bf16 in bf16_options:  # this project's default sampler against the official 50-step loop
        key = f"sample_features_dpmpp7_guided{'_bf16' if bf16 else ''}_s"
        label = f"one motion from caption features, DPM-Solver++-7 (motiondiff's default){' bf16' if bf16 else ''}"
        run, total, _ = workloads.feature_sampling(preset, frames, "dpmpp", 7, bf16=bf16)
        s.time(f"{label}, {size} preset (random weights)", run, key=key, note=f"{total} steps")
        pairs.append({"workload": f"{label} vs official DDIM-50", "motiondiff_key": key, "dtype": None,
                      "official_key": "official_sample_features_ddim50_guided_s" if code else None,
                      "note": "different samplers at matched quality: docs/results/few_step_sampling.md"})  # fmt: skip
    return pairs


def comparison_table(rows: list[dict], keys: dict[str, float], pairs: list[dict]) -> list[dict]:
    """The numbers of each pair: medians, official ÷ motiondiff, and for training and forward rows GFLOP/s and the
    share of the matmul peak in the row's dtype (``keys['matmul_<dtype>_gflops']``)."""
    by_key = {row["key"]: row for row in rows if row.get("key")}
    table = []
    for p in pairs:
        entry = {"workload": p["workload"], "note": p["note"]}
        for side in ("motiondiff", "official"):
            row = by_key.get(p[f"{side}_key"]) if p[f"{side}_key"] else None
            entry[f"{side}_s"] = row["median_s"] if row else None
            peak = keys.get(f"matmul_{p['dtype']}_gflops") if p["dtype"] else None
            if row and peak and "flops_per_s" in row:
                entry[f"{side}_gflops"] = row["flops_per_s"] / 1e9
                entry[f"{side}_peak_share"] = row["flops_per_s"] / 1e9 / peak
        if entry["official_s"] and entry["motiondiff_s"]:
            entry["official_over_motiondiff"] = entry["official_s"] / entry["motiondiff_s"]
        table.append(entry)
    return table


def _seconds(s: float | None) -> str:
    return "—" if s is None else format_seconds(s)


def _rate(entry: dict, side: str) -> str:
    gflops = entry.get(f"{side}_gflops")
    return "—" if gflops is None else f"{gflops:.1f} ({entry[f'{side}_peak_share']:.0%})"


def comparison_markdown(table: list[dict], with_official: bool) -> list[str]:
    """The side-by-side table; without the official code, the same table minus its columns."""
    rate = "GFLOP/s (share of matmul peak)"
    if with_official:
        head = f"| workload | official median | motiondiff median | official ÷ motiondiff | official {rate} | motiondiff {rate} | note |"
        lines = [head, "|---|---:|---:|---:|---:|---:|---|"]
    else:
        lines = [f"| workload | motiondiff median | motiondiff {rate} | note |", "|---|---:|---:|---|"]
    for e in table:
        ratio = e.get("official_over_motiondiff")
        if with_official:
            lines.append(f"| {e['workload']} | {_seconds(e['official_s'])} | {_seconds(e['motiondiff_s'])} | "
                         f"{'—' if ratio is None else f'{ratio:.2f}x'} | {_rate(e, 'official')} | "
                         f"{_rate(e, 'motiondiff')} | {e['note']} |")  # fmt: skip
        else:
            lines.append(
                f"| {e['workload']} | {_seconds(e['motiondiff_s'])} | {_rate(e, 'motiondiff')} | {e['note']} |"
            )
    return lines


def params_and_notes(code: OfficialCode | None, quick: bool) -> tuple[dict, list[str]]:
    """Parameter counts of both sides' networks at the compared preset, and the notes that say what differs."""
    preset = workloads.TINY if quick else "paper"
    ours = sum(p.numel() for p in workloads.build_denoiser(preset).parameters())
    if code is None:
        return {"motiondiff": ours}, [
            f"Comparison rows: {ours:,} parameters. `python bench/run.py --official <local clone of "
            "GuyTevet/motion-diffusion-model>` adds the official code's column, timed in the same run."
        ]
    model = official.build_model(code, preset)
    theirs, width, d_model = official.param_count(model), model.clip_dim, model.latent_dim
    projection, diff = (width - workloads.COND_DIM) * d_model, theirs - ours
    share = " (all of it)" if diff == projection else ""
    return {"motiondiff": ours, "official": theirs}, [
        f"Official MDM code: {code.path} at commit {code.commit}. Stubbed while it is imported (never timed): `clip` "
        "(both sides get precomputed random caption features, the official side through y['text_embed'], its own "
        "caching path) and its SMPL layer (used only by geometric losses that are 0 for HumanML3D).",
        f"Parameters: official {theirs:,} without CLIP, motiondiff {ours:,}. Its caption projection takes {width}-wide "
        f"CLIP features, this project's {workloads.COND_DIM}-wide ones (into {d_model}): {projection:,} of the "
        f"difference of {diff:,}{share}.",
        "Official training step: its loop's uniform t, training_losses, MixedPrecisionTrainer (gradient and parameter "
        "norms every step, no clipping) and AdamW; motiondiff's clips gradients at 1.0. Official DDIM-50 is its "
        "SpacedDiffusion respaced with 'ddim50' (ddim_sample_loop); its sample/generate.py default is DDPM-1000.",
    ]
