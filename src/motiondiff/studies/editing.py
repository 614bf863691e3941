"""Does editing keep what it should and change what it should? Measurements on real test clips.

    python -m motiondiff.studies.editing [checkpoint=latest] [num_edits=20] [num_part_edits=10] [split=test]
        [modes=[overwrite,repaint]] [sampler=ddim] [steps=50] [guidance=...] [resample=1] [boundary_blend=16]
        [hold_from=1] [reconstruction=0] [seed=0] [data=<prepared folder>] ["text='a person raises both hands'"]
        [parts=upper_body] [out=<folder>] [device=cpu]          (every key and its default: conf/study/editing.yaml)

(a) In-betweening of ``num_edits`` clips of the split (first and last 25% kept, each clip's own caption or action as
    the condition, boundaries blended over ``boundary_blend`` frames; with a blend, the same edits also without it):
    the largest decoded error on the kept frames (m), and per boundary the joint-speed jump
        ratio = speed of the step across the boundary / max(median step speed of the generated middle, 0.1 m/s),
    speed of a step = mean over joints of |x_{k+1} - x_k| · fps (m/s). A ratio near 1 is a seamless boundary; the
    report gives the largest ratio and the share <= 3. (The floor keeps a near-still middle from turning sensor-level
    jitter into huge ratios.)
(b) Body-part editing of ``num_part_edits`` WALKING clips (content label or caption containing "walk"; the test
    split first, then val and train if it has too few) keeping ``lower_body`` (legs and root trajectory) with
    ``text``: the largest root-relative error of the kept joints (m), and how many edits have both wrists above the
    head - wrist y above head y on the feature skeleton (SMPL-22 via the representation's bridge) for >= 25% of the
    frames - next to the same count on the unedited inputs, and the median smoothness (vvMDM) of the edits and inputs.
(c) Both modes (overwrite, repaint) with the same seed, side by side. Writes report.md and report.json.

The measurement functions are shared with ``edit.py`` (its results.json).
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import numpy as np
import torch
from tqdm import tqdm

from motiondiff.data.representations.spec import bridge_from_spec
from motiondiff.edit.api import edit_parts, inbetween
from motiondiff.edit.inputs import dataset_motions
from motiondiff.edit.masks import EditError
from motiondiff.edit.measures import SPEED_FLOOR, boundary_jumps, edit_numbers
from motiondiff.edit.smoothing import smoothness_of_joints
from motiondiff.model_files.loading import load_model as load_module
from motiondiff.model_files.resolve import find_model
from motiondiff.runtime.atomic import finite_or_null, write_json
from motiondiff.runtime.errors import UsageError
from motiondiff.runtime.paths import REPO_DIR
from motiondiff.runtime.scripting import quiet_tool_caches
from motiondiff.studies.config import study_config

MAX_RATIO = 3.0  # a boundary step at most 3x the generated middle's typical speed counts as seamless
WRISTS_UP_SHARE = 0.25  # share of frames with both wrists above the head that counts as "hands raised"


# ---- measurements (the per-edit ones: motiondiff.edit.measures) ------------------------------------------------------
def wrists_up_share(joints: np.ndarray, skeleton) -> float:
    """Share of frames with both wrists (last joint of each arm preset) above the head (last head joint)."""
    head = skeleton.parts["head"][-1]
    wrists = [skeleton.parts["left_arm"][-1], skeleton.parts["right_arm"][-1]]
    up = (np.asarray(joints)[:, wrists, 1] > np.asarray(joints)[:, [head], 1]).all(-1)
    return float(up.mean())


def low_noise_error(module, motions, t: int = 20, seed: int = 0) -> dict:
    """How well the denoiser gives back an almost clean input: root-relative MPJPE (m) of x̂0(x_t, t) against the
    clip, next to that of x_t itself (what returning the input unchanged scores). A denoiser that cannot reproduce a
    clean pose (e.g. a width below the feature size: every feature passes through d_model numbers) puts its own pose
    next to the kept frames of an edit, and the boundary jumps by about this error."""
    gen = torch.Generator().manual_seed(seed)
    pred, ident = [], []
    with torch.inference_mode():
        for m in motions:
            x0 = module.normalise(torch.as_tensor(np.asarray(m.features), dtype=torch.float32))[None]
            tt = torch.full((1,), t, dtype=torch.long, device=module.device)
            noise = torch.randn(x0.shape, generator=gen).to(x0)
            xt = module.diffusion.q_sample(x0, tt, noise)
            mask = torch.ones(x0.shape[:2], dtype=torch.bool, device=module.device)
            drop = torch.ones(1, dtype=torch.bool, device=module.device)  # unconditioned: the input alone
            x0_hat = module.diffusion.to_x0(module.denoiser(xt, tt, cond=None, mask=mask, drop_cond=drop), xt, tt)
            ref, est, inp = (module.joints(module.denormalise(v))[0].cpu().numpy() for v in (x0, x0_hat, xt))
            ref, est, inp = (v - v[:, :1] for v in (ref, est, inp))
            pred.append(float(np.linalg.norm(est - ref, axis=-1).mean()))
            ident.append(float(np.linalg.norm(inp - ref, axis=-1).mean()))
    return {"t": t, "clips": len(pred), "x0_hat_mpjpe_m": float(np.mean(pred)), "x_t_mpjpe_m": float(np.mean(ident))}


# ---- the acceptance run -------------------------------------------------------------------------------------------
def _clip_condition(module, motion):
    """The clip's own condition: its first caption (text models), its label (action models), or None."""
    if module.condition_kind == "text" and motion.captions:
        return motion.captions[0]
    if module.condition_kind == "action" and motion.label in (module.hparams.get("action_names") or []):
        return motion.label
    return None


def _raise_condition(module, text: str):
    if module.condition_kind == "text":
        return text
    names = module.hparams.get("action_names") or []
    return "raise-up-both-hands" if module.condition_kind == "action" and "raise-up-both-hands" in names else None


def walking_clips(module, split: str, count: int, data_root=None) -> list:
    """``count`` clips whose label or a caption contains "walk": from ``split`` first, then the other splits."""

    found = []
    for name in dict.fromkeys([split, "val", "train"]):
        for m in dataset_motions(module, name, data_root):
            if "walk" in (m.label or "") or any("walk" in c.lower() for c in m.captions):
                found.append(m)
        if len(found) >= count:
            break
    return found[:count]


def evaluate_editing(module, *, split, num_edits, num_part_edits, modes, text, parts, data_root, seed, boundary_blend,
                     **sampling) -> dict:  # fmt: skip
    """The numbers of the module docstring, per mode (the settings of conf/study/editing.yaml). ``sampling``:
    sampler, steps, eta, guidance, resample, hold_from, reconstruction."""

    fps = float(module.hparams.fps)
    bridge = bridge_from_spec(module.hparams.get("representation"), module.hparams.feature_dim)
    clips = dataset_motions(module, split, data_root)[:num_edits]
    walks = walking_clips(module, split, num_part_edits, data_root)
    raise_cond = _raise_condition(module, text)
    skeleton = bridge.feature_skeleton
    walk_joints = [bridge.joints(m.features) for m in walks]  # decoded once for both measures
    inputs_up = [wrists_up_share(j, skeleton) for j in walk_joints]
    report = {"split": split, "fps": fps, "sampling": sampling, "seed": seed, "boundary_blend": boundary_blend,
              "modes": {},
              "inbetween_clips": [m.source for m in clips], "parts_clips": [m.source for m in walks],
              "parts": parts, "text": raise_cond,
              "inputs_wrists_up": int(sum(s >= WRISTS_UP_SHARE for s in inputs_up)),
              "inputs_median_smoothness": float(np.median([smoothness_of_joints(j, skeleton) for j in walk_joints])),
              "inbetween_inputs_median_smoothness": float(np.median(
                  [smoothness_of_joints(bridge.joints(m.features), skeleton) for m in clips])),
              "low_noise": low_noise_error(module, clips, seed=seed)}  # fmt: skip
    for mode in tqdm(modes, desc="editing modes", unit="mode"):
        t0 = time.perf_counter()
        conds = [_clip_condition(module, m) for m in clips]
        if any(c is None for c in conds):
            conds = None  # a batch is conditioned or not
        ib = inbetween(module, clips, conds, mode=mode, seed=seed, boundary_blend=boundary_blend, **sampling)
        # the same boundaries measured on the unedited clips: what a seamless in-betweening scores
        real = [b for m, k in zip(clips, ib.kept_frames, strict=True)
                for b in boundary_jumps(m.joints, k, fps)["boundaries"]]  # fmt: skip
        for key, name in (("ratio", "inputs_boundary_ratio"), ("change_ratio", "inputs_change_ratio")):
            values = np.array([b[key] for b in real])
            report[name] = {"max": float(values.max()), "median": float(np.median(values)),
                            "share_le_3": float(np.mean(values <= MAX_RATIO))}  # fmt: skip
        bp = edit_parts(module, walks, parts, [raise_cond] * len(walks), mode=mode, seed=seed, **sampling)
        bp_rows = [edit_numbers(bp, i, fps) for i in range(len(bp))]
        edited = [bridge.joints(f) for f in bp.features]
        up = [wrists_up_share(j, skeleton) for j in edited]
        smooth = [smoothness_of_joints(j, skeleton) for j in edited]
        ib_smooth = [smoothness_of_joints(bridge.joints(f), skeleton) for f in ib.features]
        report["modes"][mode] = {
            "inbetween": inbetween_summary(
                ib, clips, fps, "clip captions/actions" if conds else "nothing (unconditioned)", ib_smooth
            ),
            "parts": {
                "edits": len(bp),
                "max_root_relative_kept_error_m": max(r["root_relative_kept_max_error_m"] for r in bp_rows),
                "max_kept_error_m": max(r["kept_max_error_m"] for r in bp_rows),
                "wrists_up_edits": int(sum(s >= WRISTS_UP_SHARE for s in up)),
                "median_smoothness": float(np.median(smooth)),
                "per_edit": [
                    {"clip": m.source, "wrists_up_share": s, "smoothness": sm, **r}
                    for m, s, sm, r in zip(walks, up, smooth, bp_rows, strict=True)
                ],
            },
            "wall_s": time.perf_counter() - t0,
        }
        if boundary_blend:  # the same edits without the blend (same seed, so the same samples before it)
            plain = inbetween(module, clips, conds, mode=mode, seed=seed, boundary_blend=0, **sampling)
            report["modes"][mode]["inbetween_plain"] = inbetween_summary(plain, clips, fps, "the same", per_edit=False)
    return report


def inbetween_summary(result, clips, fps: float, conditioned_on: str, smoothness=None, per_edit: bool = True) -> dict:
    """The in-betweening numbers of the module docstring over the edits of ``result`` (with the median of the
    edits' ``smoothness`` when given: a jittery middle would lower it)."""
    rows = [edit_numbers(result, i, fps) for i in range(len(result))]
    ratios = np.array([b["ratio"] for r in rows for b in r["boundaries"]])
    changes = np.array([b["change_ratio"] for r in rows for b in r["boundaries"]])
    summary = {
        "edits": len(result),
        "conditioned_on": conditioned_on,
        "boundary_blend": result.settings.get("boundary_blend", 0),
        "max_kept_error_m": max(r["kept_max_error_m"] for r in rows),
        "max_boundary_ratio": float(ratios.max()),
        "median_boundary_ratio": float(np.median(ratios)),
        "share_ratio_le_3": float(np.mean(ratios <= MAX_RATIO)),
        "max_change_ratio": float(changes.max()),
        "share_change_le_3": float(np.mean(changes <= MAX_RATIO)),
        "median_middle_speed": float(np.median([r["median_generated_speed"] for r in rows])),
        "median_input_middle_speed": float(np.median([r["median_input_speed"] for r in rows])),
    }
    if smoothness is not None:
        summary["median_smoothness"] = float(np.median([v for v in smoothness if v is not None]))
    if per_edit:
        summary["per_edit"] = [{"clip": m.source, **r} for m, r in zip(clips, rows, strict=True)]
    return summary


def markdown_table(header: list[str], rows: list[list[str]]) -> list[str]:
    """Lines of a Markdown table, the first column left-aligned and the numbers right-aligned."""
    lines = ["| " + " | ".join(header) + " |", "|---|" + "---:|" * (len(header) - 1)]
    return lines + ["| " + " | ".join(row) + " |" for row in rows]


def _inbetween_rows(report: dict, plain_note: str = "") -> list[tuple[str, dict]]:
    """(row name, in-betweening summary) per mode, with and without the boundary blend where both were run."""
    return [(name, r[key]) for mode, r in report["modes"].items()
            for key, name in (("inbetween", mode), ("inbetween_plain", f"{mode}, no blend{plain_note}")) if key in r]  # fmt: skip


def _smooth(value) -> str:
    return "–" if value is None else f"{value:.4f}"


def format_report(report: dict, checkpoint: str = "") -> str:
    s = report["sampling"]
    ib0 = first = next(iter(report["modes"].values()))["inbetween"]
    lines = [
        "# Motion editing on real clips",
        "",
        f"Checkpoint: `{checkpoint}`  ",
        f"Sampler: {s.get('sampler')} (steps {s.get('steps')}, eta {s.get('eta', 0.0)}, resample "
        f"{s.get('resample', 1)}), guidance {s.get('guidance') if s.get('guidance') is not None else 'model default'}, "
        f"known part held at t < {s.get('hold_from', 1.0):g}·T, reconstruction guidance "
        f"{s.get('reconstruction', 0.0):g}, seed {report['seed']}",
        "",
        f"## (a) In-betweening: {ib0['edits']} {report['split']} clips, first and last 25% kept",
        "",
        f"Conditioned on {ib0['conditioned_on']}; boundaries blended over {report.get('boundary_blend', 0)} frames "
        "(motiondiff.edit.blend; 0: plain in-painting). Ratio = speed of the step across a boundary / max(median step "
        f"speed of the generated middle, {SPEED_FLOOR} m/s); step speed = mean joint displacement x fps.",
        "",
    ]
    rows = []
    for name, a in _inbetween_rows(report, " (plain in-painting)"):
        rows.append([name, f"{a['max_kept_error_m']:.2e}", f"{a['max_boundary_ratio']:.2f}",
                     f"{a['median_boundary_ratio']:.2f}", f"{a['share_ratio_le_3']:.0%}",
                     f"{a['median_middle_speed']:.2f}", _smooth(a.get("median_smoothness"))])  # fmt: skip
    real = report["inputs_boundary_ratio"]
    rows.append(["unedited clips (reference)", "–", f"{real['max']:.2f}", f"{real['median']:.2f}",
                 f"{real['share_le_3']:.0%}", f"{first['median_input_middle_speed']:.2f}",
                 _smooth(report.get("inbetween_inputs_median_smoothness"))])  # fmt: skip
    lines += markdown_table(
        ["Mode", "Max kept-frame error (m)", "Max boundary ratio", "Median ratio", "Share of boundaries <= 3",
         "Median middle speed (m/s)", "Median smoothness"], rows,
    )  # fmt: skip
    lines += ["", "A jittery generated middle makes every boundary ratio small: compare its speed with the input's.",
              "", "Velocity change at each boundary (the larger change into or out of the boundary step, mean over "
              "joints, over the same scale): a kept part that ends in a fast movement makes a fast boundary step "
              "however seamless the edit, and only a seam changes the velocity there.", ""]  # fmt: skip
    rows = [[name, f"{a['max_change_ratio']:.2f}", f"{a['share_change_le_3']:.0%}"]
            for name, a in _inbetween_rows(report)]  # fmt: skip
    if "inputs_change_ratio" in report:
        real = report["inputs_change_ratio"]
        rows.append(["unedited clips (reference)", f"{real['max']:.2f}", f"{real['share_le_3']:.0%}"])
    lines += markdown_table(["Mode", "Max change ratio", "Share of boundaries <= 3"], rows)
    if "low_noise" in report:
        ln = report["low_noise"]
        lines += ["", f"Denoiser at t = {ln['t']} on the same clips (root-relative MPJPE): x̂0 {ln['x0_hat_mpjpe_m']:.4f} m, "
                  f"the noisy input itself {ln['x_t_mpjpe_m']:.4f} m. Where x̂0 is the worse, the model cannot give back "
                  "a clean pose, and an edit's generated frames meet the kept ones with about that jump."]  # fmt: skip
    n = len(report["parts_clips"])
    lines += [
        "",
        f"## (b) Body-part editing: `{report['parts']}` regenerated on {n} walking clips, condition {report['text']!r}",
        "",
        f"Wrists up = both wrists above the head for >= {WRISTS_UP_SHARE:.0%} of the frames (feature skeleton). "
        f"Unedited inputs with wrists up: {report['inputs_wrists_up']} of {n}. Smoothness: vvMDM's (1 = no "
        f"acceleration), median over the edits; the unedited inputs: {report.get('inputs_median_smoothness', float('nan')):.4f}.",
        "",
    ]
    rows = []
    for mode, r in report["modes"].items():
        b = r["parts"]
        rows.append([mode, f"{b['max_root_relative_kept_error_m']:.2e}", f"{b['max_kept_error_m']:.2e}",
                     f"{b['wrists_up_edits']} of {b['edits']}", f"{b.get('median_smoothness', float('nan')):.4f}"])  # fmt: skip
    lines += markdown_table(
        ["Mode", "Max root-relative kept-joint error (m)", "Max world kept-joint error (m)", "Edits with wrists up",
         "Smoothness"], rows,
    )  # fmt: skip
    lines += ["", "Clips: in-betweening " + ", ".join(report["inbetween_clips"]),
              "", "Walking clips: " + ", ".join(report["parts_clips"]), ""]  # fmt: skip
    return "\n".join(lines)


def main(argv: list[str]) -> Path:

    quiet_tool_caches()
    cfg = study_config("editing", argv)
    outputs = Path(os.environ.get("MOTIONDIFF_OUTPUT_DIR", REPO_DIR / "outputs"))
    ckpt = find_model(cfg.checkpoint, outputs)
    module = load_module(ckpt, cfg.device)
    sampling = {k: cfg[k] for k in ("sampler", "eta", "resample", "hold_from", "reconstruction", "steps")}
    if cfg.guidance is not None:
        sampling["guidance"] = cfg.guidance
    try:
        report = evaluate_editing(
            module, split=cfg.split, num_edits=cfg.num_edits, num_part_edits=cfg.num_part_edits,
            modes=tuple(cfg.modes), text=cfg.text, parts=cfg.parts, data_root=cfg.data, seed=cfg.seed,
            boundary_blend=cfg.boundary_blend, **sampling,
        )  # fmt: skip
    except EditError as err:
        raise UsageError(str(err)) from None
    out = Path(cfg.out or outputs / "edit_eval" / time.strftime("%Y-%m-%d_%H-%M-%S"))
    out.mkdir(parents=True, exist_ok=True)
    report["checkpoint"] = str(ckpt)
    text = format_report(report, str(ckpt))
    (out / "report.md").write_text(text)
    write_json(out / "report.json", finite_or_null(report))
    print(text)
    print(f"report written to {out}")
    return out


if __name__ == "__main__":
    from motiondiff.runtime.scripting import user_errors

    user_errors(main)(sys.argv[1:])
