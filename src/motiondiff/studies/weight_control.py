"""Does a local action's weight control GuidedMotion? (the user weights of the paper's energy guidance)

    python -m motiondiff.studies.weight_control checkpoint=<train_latent.py ckpt> [local_model=shipped] [captions=20]
        [weights=[0,0.5,1,1.5,2]] [samples=2] [level_steps=[15,15,20]] [rho=0.01] [final_level=specific] [seed=0]
        [out=<prefix>]                          (every key and its default: conf/study/weight_control.yaml)

For each of ``captions`` captions of the complex-motion test split (generated captions of joined real clips), the
local actions are generated once by ``local_model``; the guided action is the first one whose description walks
or runs (else the first). Every other weight stays 1, the noise is the same for every weight, and per weight we
record the distance between the final action-level latent and the guided action's latent c^k (standardised units)
and, for walking actions, the decoded motion's root travel (m). Writes <out>.json, <out>.md and <out>.png
(default docs/results/guidedmotion/weight_control).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import torch
from tqdm import tqdm

from motiondiff.eval.report import mean_ci
from motiondiff.model_files.loading import load_latent_model
from motiondiff.model_files.loading import load_model as load_module
from motiondiff.model_files.resolve import find_model
from motiondiff.runtime.atomic import finite_or_null, write_json
from motiondiff.runtime.errors import UsageError
from motiondiff.runtime.paths import REPO_DIR
from motiondiff.studies.config import study_config

DEFAULT_OUT = REPO_DIR / "docs" / "results" / "guidedmotion" / "weight_control"
MOVING = ("walk", "run", "dash", "jog", "step")
FRAMES = 160  # 8 s at 20 fps: long enough for three local actions, within the complex split's 150-196 frames


def guided_index(texts: list[str]) -> int:
    return next((k for k, t in enumerate(texts) if any(w in t.lower() for w in MOVING)), 0)


def root_travel(joints: np.ndarray) -> float:
    """Ground distance (m) between the first and last root position."""
    return float(np.linalg.norm(joints[-1, 0, [0, 2]] - joints[0, 0, [0, 2]]))


def run_caption(pipe, evaluators, text, frames, weights, samples, steps, seed, **sample_kwargs):
    """One caption's rows: its local actions planned once, then sampled at each weight of the guided action from the
    same noise (``pipe``: a GuidedMotionPipeline)."""
    module = pipe.latent
    graph, local = pipe.plan_local_actions(text, frames=frames, generator=torch.Generator().manual_seed(seed))
    k = guided_index(local.texts)
    local_feats = local.motions[k].to(module.device)
    local_embedding = evaluators.embed_motion([local_feats.cpu().numpy()])["text_motion"]
    rows = []
    for w in weights:
        user = [1.0] * len(local.texts)
        user[k] = float(w)
        feats, latents = pipe.sample_features(lengths=torch.full((samples,), frames),
                                              **pipe.caption_copies(graph, local, samples, user), steps=steps,
                                              generator=torch.Generator().manual_seed(seed + 1), return_latents=True,
                                              **sample_kwargs)  # fmt: skip
        distance = (latents["action"] - local.latents[k]).flatten(1).norm(dim=1)
        joints = module.joints(torch.from_numpy(np.stack(feats))).cpu().numpy()
        embedding = evaluators.embed_motion(feats)["text_motion"]
        rows.append({"weight": float(w), "latent_distance": distance.tolist(),
                     "root_travel_m": [root_travel(j) for j in joints],
                     "motion_distance": np.linalg.norm(embedding - local_embedding, axis=1).tolist()})  # fmt: skip
    local_joints = module.joints(local_feats[None]).cpu().numpy()[0]
    return {"text": text, "local_actions": local.texts, "guided": k, "guided_text": local.texts[k],
            "guided_local_root_travel_m": root_travel(local_joints), "rows": rows}  # fmt: skip


def summarise(results: list[dict], weights: list[float]) -> dict:
    curve = []
    for i, w in enumerate(weights):
        dist = [float(np.mean(r["rows"][i]["latent_distance"])) for r in results]
        walking = [float(np.mean(r["rows"][i]["root_travel_m"])) for r in results
                   if any(m in r["guided_text"].lower() for m in MOVING)]  # fmt: skip
        motion = [float(np.mean(r["rows"][i]["motion_distance"])) for r in results if "motion_distance" in r["rows"][i]]
        curve.append({"weight": w, "latent_distance": mean_ci(dist), "root_travel_m": mean_ci(walking) if walking else None,
                      "walking_captions": len(walking), "motion_distance": mean_ci(motion) if motion else None})  # fmt: skip
    means = [c["latent_distance"][0] for c in curve]
    monotone = all(a > b for a, b in zip(means, means[1:], strict=False))
    per_caption = sum(
        bool(np.all(np.diff([np.mean(row["latent_distance"]) for row in r["rows"]]) < 0)) for r in results
    )
    walking = [r for r in results if any(m in r["guided_text"].lower() for m in MOVING)]

    def gap(r, row):  # |decoded travel - the local motion's own travel|
        return abs(np.mean(r["rows"][row]["root_travel_m"]) - r["guided_local_root_travel_m"])

    toward = sum(bool(gap(r, -1) < gap(r, 0)) for r in walking)
    local_travel = mean_ci([r["guided_local_root_travel_m"] for r in walking]) if walking else None
    closer = sum(bool(np.mean(r["rows"][-1]["motion_distance"]) < np.mean(r["rows"][0]["motion_distance"]))
                 for r in results if "motion_distance" in r["rows"][0])  # fmt: skip
    return {"captions_decoded_closer": closer, "curve": curve, "mean_distance_decreases_monotonically": monotone, "captions_monotone": per_caption,
            "walking_captions_toward_local": toward, "walking_captions": len(walking),
            "guided_local_root_travel_m": local_travel}  # fmt: skip


def write(out: Path, meta: dict, results: list[dict], summary: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out.parent.mkdir(parents=True, exist_ok=True)
    write_json(out.with_suffix(".json"), finite_or_null({**meta, **summary, "captions": results}))
    lines = [f"# GuidedMotion weight control ({len(results)} captions)", "",
             f"Checkpoint: `{meta['checkpoint']}`; local actions by `{meta['local_model']}`; level steps {meta['level_steps']}; "
             f"{meta['samples']} samples per caption and weight; rho {meta['rho']:g}; decoded from the {meta['final_level']} "
             f"level; seed {meta['seed']}. Captions are **generated** (joined real clips).", "",
             "| weight | latent distance to c^k (mean ± 95% CI) | decoded motion's evaluator distance to the local motion "
             "| root travel of walking guided actions (m) |", "|---:|---:|---:|---:|"]  # fmt: skip
    for c in summary["curve"]:
        travel = (
            "–"
            if c["root_travel_m"] is None
            else f"{c['root_travel_m'][0]:.2f} ± {c['root_travel_m'][1]:.2f} ({c['walking_captions']})"
        )
        motion = (
            "–" if c["motion_distance"] is None else f"{c['motion_distance'][0]:.3f} ± {c['motion_distance'][1]:.3f}"
        )
        lines.append(
            f"| {c['weight']:g} | {c['latent_distance'][0]:.3f} ± {c['latent_distance'][1]:.3f} | {motion} | {travel} |"
        )
    lines += ["", f"Mean distance decreases monotonically: **{summary['mean_distance_decreases_monotonically']}**; "
              f"captions whose own curve is monotone: {summary['captions_monotone']} of {len(results)}.", "",
              f"Decoded motions closer to the guided local motion (text-motion evaluator's motion embedding) at weight "
              f"{summary['curve'][-1]['weight']:g} than at {summary['curve'][0]['weight']:g}: "
              f"**{summary['captions_decoded_closer']} of {len(results)}** captions.", ""]  # fmt: skip
    if summary["walking_captions"]:
        travel, ci = summary["guided_local_root_travel_m"]
        lines += [f"Walking guided actions: their local motions travel {travel:.2f} ± {ci:.2f} m; raising the weight "
                  f"0 → {summary['curve'][-1]['weight']:g} moves the decoded root travel towards it in "
                  f"**{summary['walking_captions_toward_local']} of {summary['walking_captions']}** captions.", ""]  # fmt: skip
    out.with_suffix(".md").write_text("\n".join(lines))
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.5))
    w = [c["weight"] for c in summary["curve"]]
    for ax, key, label in ((axes[0], "latent_distance", "‖z^a − c^k‖ (standardised)"),
                           (axes[1], "motion_distance", "evaluator distance, decoded ↔ local motion")):  # fmt: skip
        if summary["curve"][0][key] is None:
            continue
        m = np.array([c[key] for c in summary["curve"]])
        ax.errorbar(w, m[:, 0], yerr=m[:, 1], marker="o", capsize=3)
        ax.set_xlabel("weight w_k of the guided local action")
        ax.set_ylabel(label)
    fig.suptitle("GuidedMotion: local-action weight control")
    fig.tight_layout()
    fig.savefig(out.with_suffix(".png"), dpi=120)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    from motiondiff.data.datamodules import PreparedDataModule  # lazy: lightning (+4.4 s to import)
    from motiondiff.eval.protocol import Evaluators  # lazy: torchmetrics (+2.6 s to import)
    from motiondiff.pipelines.guided import GuidedMotionPipeline  # lazy: lightning, spacy (+5.1 s to import)

    cfg = study_config("weight_control", argv if argv is not None else sys.argv[1:])
    if cfg.final_level not in ("action", "specific"):
        raise UsageError(
            f"final_level must be action or specific (the guided action latent must exist), got {cfg.final_level!r}"
        )
    if len(cfg.level_steps) != 3:
        raise UsageError(f"level_steps must be three numbers [motion, action, specific], got {list(cfg.level_steps)}")
    ckpt = Path(cfg.checkpoint)
    mdm = load_module(find_model(cfg.local_model, REPO_DIR / "outputs"))
    pipe = GuidedMotionPipeline(load_latent_model(ckpt), mdm, str(ckpt))
    data = Path(cfg.data or REPO_DIR / "data" / "bandai_mini_compositional")
    evaluators = Evaluators.load(REPO_DIR / "checkpoints" / "evaluators" / data.name).for_module(mdm)
    weights = list(cfg.weights)
    steps = dict(zip(("motion", "action", "specific"), cfg.level_steps, strict=True))
    seed, samples, final_level = cfg.seed, cfg.samples, cfg.final_level
    sample_kwargs = {"rho": cfg.rho, "final_level": final_level}
    dm = PreparedDataModule(data, max_frames=196)
    dm.setup("test")
    records = dm.dataset("test").records[: cfg.captions]
    results = []
    for i, rec in enumerate(tqdm(records, desc="captions", unit="caption")):
        results.append(run_caption(pipe, evaluators, rec.texts[0], FRAMES, weights, samples, steps, seed + i,
                                   **sample_kwargs))  # fmt: skip
        tqdm.write(f"[{i + 1}/{len(records)}] {rec.texts[0][:70]!r}: guided {results[-1]['guided_text']!r}")
    meta = {"checkpoint": str(ckpt), "local_model": cfg.local_model, "weights": weights,
            "samples": samples, "level_steps": steps, "seed": seed, **sample_kwargs}  # fmt: skip
    summary = summarise(results, weights)
    out = Path(cfg.out or DEFAULT_OUT)
    write(out, meta, results, summary)
    print(json.dumps(summary["curve"], indent=1))
    print(f"written {out}.md/.json/.png")
    return 0


if __name__ == "__main__":
    from motiondiff.runtime.scripting import user_errors

    sys.exit(user_errors(main)())
