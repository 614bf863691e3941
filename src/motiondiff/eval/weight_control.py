"""Does a local action's weight control GuidedMotion? (issue 7: "weight control works")

    python -m motiondiff.eval.weight_control checkpoint=<train_latent.py ckpt> [local_model=shipped] [captions=20]
        [weights=0,0.5,1,1.5,2] [samples=2] [level_steps=15,15,20] [seed=0] [out=<prefix>]

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

from motiondiff.cli.common import REPO_DIR, UsageError, find_checkpoint, key_value_args, text_encoder_kwargs
from motiondiff.eval.report import mean_ci

KEYS = ("checkpoint", "local_model", "captions", "weights", "samples", "level_steps", "seed", "out", "data")
DEFAULT_OUT = REPO_DIR / "docs" / "results" / "guidedmotion" / "weight_control"
MOVING = ("walk", "run", "dash", "jog", "step")
FRAMES = 160  # 8 s at 20 fps: long enough for three local actions, within the complex split's 150-196 frames


def guided_index(texts: list[str]) -> int:
    return next((k for k, t in enumerate(texts) if any(w in t.lower() for w in MOVING)), 0)


def root_travel(joints: np.ndarray) -> float:
    """Ground distance (m) between the first and last root position."""
    return float(np.linalg.norm(joints[-1, 0, [0, 2]] - joints[0, 0, [0, 2]]))


def run_caption(module, mdm, encoder, text, frames, weights, samples, steps, seed):
    from motiondiff.guided.local_actions import guided_sample, local_actions_for

    gen = torch.Generator().manual_seed(seed)
    graph, local = local_actions_for(module, text, mdm=mdm, frames=frames, generator=gen)
    k = guided_index(local.texts)
    rows = []
    for w in weights:
        user = [1.0] * len(local.texts)
        user[k] = float(w)
        feats, latents = guided_sample(module, graph, encoder, local, torch.full((samples,), frames), weights=user,
                                       steps=steps, generator=torch.Generator().manual_seed(seed + 1),
                                       return_latents=True)  # fmt: skip
        distance = (latents["action"] - local.latents[k]).flatten(1).norm(dim=1)
        joints = module.joints(module.denormalise(feats)).cpu().numpy()
        rows.append({"weight": float(w), "latent_distance": distance.tolist(),
                     "root_travel_m": [root_travel(j) for j in joints]})  # fmt: skip
    local_joints = module.joints(local.motions[k][None].to(module.device)).cpu().numpy()[0]
    return {"text": text, "local_actions": local.texts, "guided": k, "guided_text": local.texts[k],
            "guided_local_root_travel_m": root_travel(local_joints), "rows": rows}  # fmt: skip


def summarise(results: list[dict], weights: list[float]) -> dict:
    curve = []
    for i, w in enumerate(weights):
        dist = [float(np.mean(r["rows"][i]["latent_distance"])) for r in results]
        walking = [float(np.mean(r["rows"][i]["root_travel_m"])) for r in results
                   if any(m in r["guided_text"].lower() for m in MOVING)]  # fmt: skip
        curve.append({"weight": w, "latent_distance": mean_ci(dist), "root_travel_m": mean_ci(walking) if walking else None,
                      "walking_captions": len(walking)})  # fmt: skip
    means = [c["latent_distance"][0] for c in curve]
    monotone = all(a > b for a, b in zip(means, means[1:], strict=False))
    per_caption = sum(
        all(np.mean(a["latent_distance"]) > np.mean(b["latent_distance"]) for a, b in zip(r["rows"], r["rows"][1:], strict=False))
        for r in results
    )  # fmt: skip
    return {"curve": curve, "mean_distance_decreases_monotonically": monotone, "captions_monotone": per_caption}


def write(out: Path, meta: dict, results: list[dict], summary: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".json").write_text(json.dumps({**meta, **summary, "captions": results}, indent=1))
    lines = [f"# GuidedMotion weight control ({len(results)} captions)", "",
             f"Checkpoint: `{meta['checkpoint']}`; local actions by `{meta['local_model']}`; level steps {meta['level_steps']}; "
             f"{meta['samples']} samples per caption and weight; seed {meta['seed']}. Captions are **generated** (joined real clips).", "",
             "| weight | latent distance to c^k (mean ± 95% CI) | root travel of walking guided actions (m) |", "|---:|---:|---:|"]  # fmt: skip
    for c in summary["curve"]:
        travel = (
            "–"
            if c["root_travel_m"] is None
            else f"{c['root_travel_m'][0]:.2f} ± {c['root_travel_m'][1]:.2f} ({c['walking_captions']})"
        )
        lines.append(f"| {c['weight']:g} | {c['latent_distance'][0]:.3f} ± {c['latent_distance'][1]:.3f} | {travel} |")
    lines += ["", f"Mean distance decreases monotonically: **{summary['mean_distance_decreases_monotonically']}**; "
              f"captions whose own curve is monotone: {summary['captions_monotone']} of {len(results)}.", ""]  # fmt: skip
    out.with_suffix(".md").write_text("\n".join(lines))
    fig, ax = plt.subplots(figsize=(5, 3.5))
    w = [c["weight"] for c in summary["curve"]]
    m = np.array([c["latent_distance"] for c in summary["curve"]])
    ax.errorbar(w, m[:, 0], yerr=m[:, 1], marker="o", capsize=3)
    ax.set_xlabel("weight w_k of the guided local action")
    ax.set_ylabel("‖z^a − c^k‖ (standardised)")
    ax.set_title("GuidedMotion: local-action weight control")
    fig.tight_layout()
    fig.savefig(out.with_suffix(".png"), dpi=120)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    from motiondiff.cli.sample import load_module
    from motiondiff.data.datamodules import PreparedDataModule
    from motiondiff.lit.latent import HierarchicalLatentModule
    from motiondiff.text.encoders import build_text_encoder

    args = key_value_args(argv if argv is not None else sys.argv[1:], KEYS)
    if "checkpoint" not in args:
        raise UsageError(
            "usage: python -m motiondiff.eval.weight_control checkpoint=<train_latent.py ckpt> [key=value ...]"
        )
    ckpt = Path(args["checkpoint"])
    module = HierarchicalLatentModule.load_from_checkpoint(ckpt, map_location="cpu", weights_only=True).eval()
    mdm = load_module(find_checkpoint(args.get("local_model", "shipped"), REPO_DIR / "outputs"))
    encoder = build_text_encoder(**text_encoder_kwargs(module.hparams.text_encoder))
    weights = [float(w) for w in args.get("weights", "0,0.5,1,1.5,2").split(",")]
    steps = dict(
        zip(("motion", "action", "specific"), map(int, args.get("level_steps", "15,15,20").split(",")), strict=True)
    )
    seed, samples = int(args.get("seed", 0)), int(args.get("samples", 2))
    dm = PreparedDataModule(args.get("data", REPO_DIR / "data" / "bandai_mini_compositional"), max_frames=196)
    dm.setup("test")
    records = dm.dataset("test").records[: int(args.get("captions", 20))]
    results = []
    for i, rec in enumerate(records):
        results.append(run_caption(module, mdm, encoder, rec.texts[0], FRAMES, weights, samples, steps, seed + i))
        print(f"[{i + 1}/{len(records)}] {rec.texts[0][:70]!r}: guided {results[-1]['guided_text']!r}", flush=True)
    meta = {"checkpoint": str(ckpt), "local_model": args.get("local_model", "shipped"), "weights": weights,
            "samples": samples, "level_steps": steps, "seed": seed}  # fmt: skip
    summary = summarise(results, weights)
    out = Path(args.get("out", DEFAULT_OUT))
    write(out, meta, results, summary)
    print(json.dumps(summary["curve"], indent=1))
    print(f"written {out}.md/.json/.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
