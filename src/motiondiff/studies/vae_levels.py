"""How well each of GuidedMotion's three motion VAEs reconstructs real motion (paper Tab. 5 / Tab. C).

    python -m motiondiff.studies.vae_levels [motion=<ckpt>] [action=<ckpt>] [specific=<ckpt>] [out=<prefix>]
                                         [split=test] [replications=20] [seed=0] [data=<dataset root>]
                                         [evaluator_dir=checkpoints/evaluators/<dataset>]
    (every key and its default: conf/study/vae_levels.yaml)

Each test clip is encoded, its posterior mean decoded, and the reconstruction compared with the clip: MPJPE in
metres (global joints as decoded, and root-aligned as MLD reports), then the evaluate.py protocol with the
reconstructions as the "generated" set (FID against the real clips, R-precision, Diversity; 20 replications of
the caption draw, mean ± 95% CI). A level left out is the newest run's best-MPJPE checkpoint under outputs/vae/<level>.
Writes <out>.md and <out>.json (default docs/results/guidedmotion/vae_levels).
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import numpy as np
import torch
from tqdm import tqdm

from motiondiff.eval import report
from motiondiff.eval.protocol import EvalClips, Evaluators, pad, replication_metrics
from motiondiff.lit.vae import MotionVAEModule, mpjpe
from motiondiff.model_files.loading import load_vae
from motiondiff.models.vae import LEVEL_TOKENS
from motiondiff.runtime.best_checkpoints import best_of
from motiondiff.runtime.errors import UsageError
from motiondiff.runtime.paths import REPO_DIR, shown
from motiondiff.runtime.scripting import quiet_tool_caches, register_resolvers
from motiondiff.studies.config import study_config

DEFAULT_OUT = REPO_DIR / "docs" / "results" / "guidedmotion" / "vae_levels"
# column key, header (metric keys come from lit.vae.mpjpe and protocol.replication_metrics)
COLUMNS = (("mpjpe", "MPJPE (m) ↓"), ("mpjpe_root", "root-aligned MPJPE (m) ↓"), ("fid", "FID ↓"),
           ("r_precision_top3", "R-Precision top-3 ↑"), ("diversity", "Diversity →"))  # fmt: skip


def newest_checkpoint(level: str, outputs: Path) -> Path:
    found = sorted((outputs / "vae" / level).glob("**/checkpoints/best-mpjpe-*.ckpt"), key=lambda p: p.stat().st_mtime)
    if not found:
        raise UsageError(
            f"no trained {level} VAE under {outputs / 'vae' / level}: train one (`python train_vae.py level={level}`) "
            f"or pass {level}=<path to a .ckpt>"
        )
    newest_run = found[-1].parent  # within it, the lowest saved MPJPE (a resumed run may hold a stale best file)
    return best_of(sorted(newest_run.glob("best-mpjpe-*.ckpt")), "val/mpjpe") or found[-1]


def load_level(path: Path) -> tuple[MotionVAEModule, dict]:
    """The module (eval mode) and what the report needs from the checkpoint and its run's run.json."""
    module, step = load_vae(path, "checkpoint", "pass <level>=<path to a train_vae.py .ckpt>")
    run_json = path.parent.parent / "run.json"
    run = json.loads(run_json.read_text()) if run_json.is_file() else {}
    info = {"checkpoint": shown(path), "tokens": module.tokens, "step": step,
            "run_steps": run.get("train_steps"), "train_seconds": run.get("train_seconds"),
            "overrides": run.get("overrides"), "parameters": sum(p.numel() for p in module.vae.parameters())}  # fmt: skip
    return module, info


def datamodule(module: MotionVAEModule, data_root: str | None):
    """The checkpoint's dataset as train_vae.py builds it (its conf/dataset entry), in its representation."""
    from hydra import compose, initialize_config_dir
    from hydra.utils import instantiate

    register_resolvers()
    hp = module.hparams
    if not hp.dataset:
        raise UsageError("the checkpoint does not name its dataset; train it with train_vae.py (which records it)")
    overrides = [f"dataset={hp.dataset}"] + ([f"dataset.root={data_root}"] if data_root else [])
    with initialize_config_dir(version_base="1.3", config_dir=str(REPO_DIR / "conf")):
        cfg = compose("train_vae", overrides=overrides)
    rep = (hp.get("representation") or {}).get("name")
    dm = instantiate(cfg.dataset.datamodule, max_frames=hp.max_frames, **({"representation": rep} if rep else {}))
    dm.setup(None)
    return dm


@torch.inference_mode()
def reconstruct(module: MotionVAEModule, features: list[np.ndarray], batch_size: int = 64) -> list[np.ndarray]:
    """De-normalised features of clips -> their reconstructions, decoded from the posterior mean."""
    recons = []
    for s in range(0, len(features), batch_size):
        x, lengths = pad(features[s : s + batch_size])
        mask = torch.arange(x.shape[1])[None] < lengths[:, None]
        recon = module.denormalise(module.reconstruct(module.normalise(x), mask))
        recons += [r[:n].numpy() for r, n in zip(recon, lengths.tolist(), strict=True)]
    return recons


def mean_motion(module: MotionVAEModule, features: list[np.ndarray]) -> list[np.ndarray]:
    """The dataset's mean feature vector at every frame: what a VAE that ignores its input would decode."""
    return [np.broadcast_to(module.mean.numpy(), f.shape).copy() for f in features]


@torch.inference_mode()
def clip_errors(module: MotionVAEModule, real: list[np.ndarray], recons: list[np.ndarray]) -> dict[str, np.ndarray]:
    """Per-clip MPJPE in metres of the joints the representation decodes: global, and root-aligned."""
    (x, lengths), (r, _) = pad(real), pad(recons)
    mask = torch.arange(x.shape[1])[None] < lengths[:, None]
    pred, true = module.joints(r), module.joints(x)
    return {"mpjpe": mpjpe(pred, true, mask).numpy(), "mpjpe_root": mpjpe(pred, true, mask, root_aligned=True).numpy()}


def evaluate_levels(modules: dict[str, MotionVAEModule], dm, evaluators: Evaluators, split: str = "test",
                    replications: int = 20, seed: int = 0) -> tuple[dict, dict]:  # fmt: skip
    """({"Real": summary, "mean motion": summary, level: summary}, {level: per-clip MPJPE}); a summary is
    {metric: (mean, ci, n)}."""
    test, train = EvalClips.from_dataset(dm.dataset(split)), EvalClips.from_dataset(dm.dataset("train"))
    kind = "text" if evaluators.text_motion is not None and all(test.captions) else "none"
    real_test, real_train = evaluators.embed_motion(test.features), evaluators.embed_motion(train.features)
    captions = [test.pick_captions(np.random.default_rng(seed + r)) for r in range(replications)]
    texts = [evaluators.embed_text(c) if kind == "text" else None for c in captions]

    def protocol(reference: dict, generated: dict) -> list[dict]:  # evaluate.py's replications
        return [replication_metrics(kind, evaluators, reference, generated, text=texts[r], seed=seed + r,
                                    pool_size=32) for r in range(replications)]  # fmt: skip

    rows = {"Real": report.summarise(protocol(real_train, real_test))}
    per_clip = {}
    first = next(iter(modules.values()))
    candidates = {"mean motion": (first, mean_motion(first, test.features))}
    candidates.update({level: (m, reconstruct(m, test.features)) for level, m in modules.items()})
    for name, (module, recons) in tqdm(candidates.items(), desc="VAE rows", unit="row"):
        rows[name] = report.summarise(protocol(real_test, evaluators.embed_motion(recons)))
        for key, errors in clip_errors(module, test.features, recons).items():
            rows[name][key] = (*report.mean_ci(errors), len(errors))
            if key == "mpjpe" and name in modules:
                per_clip[name] = errors
    return rows, per_clip


def paired(per_clip: dict[str, np.ndarray]) -> list[dict]:
    """Each larger-Q level against each smaller one on the same clips: how often and by how much it is better."""
    out = []
    levels = list(per_clip)
    for i, small in enumerate(levels):
        for large in levels[i + 1 :]:
            diff = per_clip[large] - per_clip[small]
            mean, ci = report.mean_ci(diff)
            out.append({"levels": [small, large], "clips_lower": int((diff < 0).sum()), "clips": len(diff),
                        "mean_difference_m": mean, "ci95_m": ci})  # fmt: skip
    return out


def _cell(summary: dict, key: str) -> str:
    if key not in summary:
        return report.MISSING
    mean, ci, _ = summary[key]
    return report.format_cell(mean, ci) if ci > 0 else f"{mean:.3f}"


def trend(rows: dict, pairs: list[dict], levels: list[str]) -> list[str]:
    """Whether the paper's finding (more tokens, better reconstruction) holds here, per metric, in words."""
    out = []
    metrics = (("mpjpe", "MPJPE", -1), ("mpjpe_root", "root-aligned MPJPE", -1), ("fid", "FID", -1),
               ("r_precision_top3", "R-precision top-3", 1))  # fmt: skip
    for key, name, better in metrics:
        if not all(key in rows[lv] for lv in levels):
            continue
        values = [rows[lv][key][0] for lv in levels]
        holds = all(better * (b - a) > 0 for a, b in zip(values, values[1:], strict=False))
        chain = ", ".join(f"{lv} {v:.3f}" for lv, v in zip(levels, values, strict=True))
        out.append(f"paper's trend (more tokens, better) on {name}: {'holds' if holds else 'does not hold'} ({chain})")
    clear = [f"{p['levels'][1]} {'<' if p['mean_difference_m'] < 0 else '>'} {p['levels'][0]}"
             for p in pairs if abs(p["mean_difference_m"]) > p["ci95_m"]]  # fmt: skip
    out.append("paired MPJPE differences whose 95% CI excludes 0: " + (", ".join(clear) or "none"))
    if "fid" in rows.get("Real", {}):
        out.append(f"for scale: the real test and train clips are FID {rows['Real']['fid'][0]:.2f} apart; one "
                   "training run per level")  # fmt: skip
    return out


def format_table(rows: dict, infos: dict, pairs: list[dict], notes: list[str]) -> str:
    head = ["Level", "Q", *(h for _, h in COLUMNS), "Params", "Best step / run steps", "Train time"]
    lines = ["### Motion VAE levels (GuidedMotion Tab. 5)", "", "| " + " | ".join(head) + " |",
             "|" + "|".join(["---"] + [":---:"] * (len(head) - 1)) + "|"]  # fmt: skip
    for name, summary in rows.items():
        info = infos.get(name, {})
        steps = f"{info['step']} / {info['run_steps'] or '?'}" if info else "–"
        time_s = f"{info['train_seconds'] / 60:.1f} min" if info.get("train_seconds") else "–"
        params = f"{info['parameters'] / 1e6:.2f} M" if info else "–"
        cells = [name, str(info.get("tokens", "–")), *(_cell(summary, k) for k, _ in COLUMNS), params, steps, time_s]
        lines.append("| " + " | ".join(cells) + " |")
    lines.append("")
    for p in pairs:
        small, large = p["levels"]
        lines.append(f"- {large} (Q={infos[large]['tokens']}) vs {small} (Q={infos[small]['tokens']}): lower MPJPE on "
                     f"{p['clips_lower']} of {p['clips']} test clips; MPJPE difference ({large} − {small}) "
                     f"{p['mean_difference_m']:+.4f} ± {p['ci95_m']:.4f} m")  # fmt: skip
    lines += [f"- {n}" for n in notes]
    return "\n".join(lines) + "\n"


def main(argv: list[str]) -> Path:

    quiet_tool_caches()
    cfg = study_config("vae_levels", argv)
    outputs = Path(os.environ.get("MOTIONDIFF_OUTPUT_DIR", REPO_DIR / "outputs"))
    paths = {lv: Path(cfg[lv]) if cfg[lv] is not None else newest_checkpoint(lv, outputs) for lv in LEVEL_TOKENS}
    loaded = {lv: load_level(p) for lv, p in paths.items()}
    modules, infos = {lv: m for lv, (m, _) in loaded.items()}, {lv: i for lv, (_, i) in loaded.items()}
    first = modules["motion"].hparams
    for lv, m in modules.items():
        if (m.hparams.dataset, m.hparams.feature_dim) != (first.dataset, first.feature_dim):
            raise UsageError(f"the {lv} VAE was trained on {m.hparams.dataset!r}, the motion VAE on {first.dataset!r}")
    dm = datamodule(modules["motion"], cfg.data)
    folder = shown(cfg.evaluator_dir or REPO_DIR / "checkpoints" / "evaluators" / first.dataset)
    try:
        evaluators = Evaluators.load(REPO_DIR / folder, num_joints=first.num_joints).for_module(modules["motion"])
    except FileNotFoundError as err:
        raise UsageError(str(err)) from None
    split, reps, seed = cfg.split, cfg.replications, cfg.seed
    if reps < 1:
        raise UsageError(f"replications must be >= 1, got {reps}")
    rows, per_clip = evaluate_levels(modules, dm, evaluators, split, reps, seed)
    pairs = paired(per_clip)
    n_clips = len(per_clip["motion"])
    notes = (
        trend(rows, pairs, list(LEVEL_TOKENS))
        + [
            f"{first.dataset}, {split} split, {n_clips} clips; reconstructions decode the posterior mean",
            "MPJPE: mean ± 95% CI over clips (global joints as decoded; root-aligned: each frame moved to its root)",
            f"FID / R-precision / Diversity: the shipped evaluators ({folder}), {reps} replications of the caption draw "
            "(mean ± 95% CI); reconstructions are scored against the real clips, as evaluate.py scores samples. FID of "
            "a deterministic reconstruction does not vary between replications, so it has no CI",
            "Real: the real test clips scored against the real train clips (evaluate.py's Real row); mean motion: the "
            "dataset's mean features at every frame (what a VAE that ignores its input decodes)",
        ]
        + [f"{lv}: `python train_vae.py {' '.join(i['overrides'])}`" for lv, i in infos.items() if i.get("overrides")]
    )
    text = format_table(rows, infos, pairs, notes)
    out = Path(cfg.out or DEFAULT_OUT)
    out.parent.mkdir(parents=True, exist_ok=True)
    report.write_markdown(out.with_suffix(".md"), text)
    data = {"rows": {k: {m: list(v) for m, v in s.items()} for k, s in rows.items()}, "levels": infos,
            "paired_mpjpe": pairs, "per_clip_mpjpe_m": {k: v.tolist() for k, v in per_clip.items()},
            "split": split, "replications": reps, "seed": seed, "evaluator_dir": folder, "notes": notes}  # fmt: skip
    payload = json.dumps(data, indent=1, allow_nan=False, ensure_ascii=False) + "\n"
    report.atomic_write(out.with_suffix(".json"), lambda tmp: Path(tmp).write_text(payload, encoding="utf-8"))
    print(text)
    print(f"written to {out}.md and {out}.json")
    return out


if __name__ == "__main__":
    from motiondiff.runtime.scripting import user_errors

    user_errors(main)(sys.argv[1:])
