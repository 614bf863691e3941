"""GuidedMotion against plain MDM on the complex-motion test split, its Tab. 4-style ablation and sampling times.
Captions are **generated** (joined real clips, `data/bandai_mini_compositional`).

    python -m motiondiff.studies.guided_compare latent=<train_latent.py ckpt> mdm=<train.py ckpt>
        [local_model=<ckpt>] [replications=5] [level_steps=[15,15,20]] [mdm_steps=50] [local_frames=60]
        [timing_repeats=5] [timing_only=false] [seed=0] [out=<prefix>] [data=<prepared dir>] [evaluators=<dir>]
        (every key and its default: conf/study/guided_compare.yaml)

Every row samples the same test captions at the real clips' lengths, and goes through the same evaluators
(`checkpoints/evaluators/bandai_mini_compositional`): R-precision, FID, MM-Dist and Diversity, mean ± 95% CI over
the replications (new noise and new local actions each time). The local actions of the guided rows are generated
by ``local_model`` (default: the compared MDM model itself, so GuidedMotion uses no model that MDM lacks); their
descriptions come from each caption's semantic graph. Writes <out>.md and <out>.json
(default docs/results/guidedmotion/comparison); ``timing_only=true`` measures only the sampling times, into
<out>_timing.md/.json. Times use the process's torch threads (set OMP_NUM_THREADS to compare machines).
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np
import torch
from tqdm import tqdm

from motiondiff.bench.timing import median_seconds as timed_median
from motiondiff.eval.report import format_markdown, summarise, write_markdown
from motiondiff.lit.conditions import condition_batch
from motiondiff.model_files.loading import load_latent_model
from motiondiff.model_files.loading import load_model as load_module
from motiondiff.model_files.resolve import find_model
from motiondiff.runtime.atomic import finite_or_null, write_json
from motiondiff.runtime.errors import UsageError
from motiondiff.runtime.paths import REPO_DIR, shown
from motiondiff.studies.config import study_config

DEFAULT_OUT = REPO_DIR / "docs" / "results" / "guidedmotion" / "comparison"
# Tab. 4's rows: (level the hierarchy stops at and decodes, local-action energy guidance on)
ABLATION = {
    "motion level": ("motion", False),
    "motion + action levels": ("action", False),
    "all three levels": ("specific", False),
    "motion + action levels + guidance": ("action", True),
    "GuidedMotion (all levels + guidance)": ("specific", True),
}
MDM_ROW = "MDM (x0, DDIM-{steps})"


def local_latents(latent, mdm, graphs, frames: int, generator: torch.Generator, steps: int = 50) -> torch.Tensor:
    """(B, A_max, Q_a, D') standardised action-level latents c^k: one MDM motion per local description of each
    caption graph (all descriptions in batched calls), zero rows past a caption's action count."""
    from motiondiff.eval.protocol import generate  # lazy: torchmetrics (+2.6 s to import)
    from motiondiff.guided.local_actions import encode_local_motions  # lazy: spacy (+0.7 s to import)

    texts = [g.action_texts() for g in graphs]
    flat = [t for ts in texts for t in ts]
    motions = generate(mdm, flat, torch.full((len(flat),), frames), generator=generator, guidance=mdm.default_guidance,
                       sampler="ddim", steps=steps)  # fmt: skip
    encoded = encode_local_motions(latent, [torch.as_tensor(m) for m in motions])
    out = torch.zeros(len(graphs), max(max(len(ts) for ts in texts), 1), *encoded.shape[1:])
    k = 0
    for i, ts in enumerate(texts):
        out[i, : len(ts)] = encoded[k : k + len(ts)]
        k += len(ts)
    return out


def guided_features(pipe, table, captions, lengths, steps, final_level, refs, generator):
    """De-normalised GuidedMotion features, one per caption, at its length (``refs``: local latents or None), through
    the pipeline's batched sampling (checked finite)."""
    graphs, feats = [table[c][0] for c in captions], [table[c][1] for c in captions]
    return pipe.sample_features(graphs, lengths, node_features=feats, local_latents=refs, steps=steps,
                                final_level=final_level, generator=generator)  # fmt: skip


def replication(pipe, mdm, evaluators, clips, table, r: int, args: dict) -> dict[str, dict]:
    from motiondiff.eval.protocol import generate, replication_metrics  # lazy: torchmetrics (+2.6 s to import)

    seed = int(args["seed"]) * 1000 + r
    captions = clips.pick_captions(np.random.default_rng(seed))
    lengths = clips.lengths
    real = evaluators.embed_motion(clips.features)
    text = evaluators.embed_text(captions)
    graphs = [table[c][0] for c in captions]
    gen = torch.Generator().manual_seed(seed)
    refs = local_latents(pipe.latent, pipe.local_model, graphs, args["local_frames"], gen, args["mdm_steps"])
    rows = {}
    for name, (level, guided) in ABLATION.items():
        feats = guided_features(pipe, table, captions, lengths, args["level_steps"], level, refs if guided else None,
                                torch.Generator().manual_seed(seed))  # fmt: skip
        rows[name] = replication_metrics("text", evaluators, real, evaluators.embed_motion(feats), text=text, seed=seed)
    feats = generate(mdm, captions, lengths, generator=torch.Generator().manual_seed(seed),
                     guidance=mdm.default_guidance, sampler="ddim", steps=args["mdm_steps"])  # fmt: skip
    name = MDM_ROW.format(steps=args["mdm_steps"])
    rows[name] = replication_metrics("text", evaluators, real, evaluators.embed_motion(feats), text=text, seed=seed)
    return rows


def median_seconds(fn, repeats: int) -> float:
    """Median of ``repeats`` timed calls after one untimed warm-up (the bench's helper)."""
    return timed_median(fn, repeats=repeats, warmup=1)["median_s"]


def sampling_times(pipe, mdm, table, caption: str, frames: int, args: dict) -> dict[str, float]:
    """Median seconds for one motion of ``frames`` frames from ``caption``, guidance on, in this process."""
    graph, feats = table[caption]
    lengths = torch.tensor([frames])

    def plan():  # the local actions' latents (MDM motions + action-VAE encoding)
        gen = torch.Generator().manual_seed(0)
        return local_latents(pipe.latent, pipe.local_model, [graph], args["local_frames"], gen, args["mdm_steps"])

    refs = plan()
    steps, repeats = args["level_steps"], args["timing_repeats"]
    cond = condition_batch(mdm, [caption])
    times = {
        "guidedmotion_latent_s": median_seconds(
            lambda: pipe.sample_features([graph], lengths, node_features=[feats], steps=steps, local_latents=refs),
            repeats,
        ),
        "guidedmotion_local_actions_s": median_seconds(plan, repeats),
        "mdm_s": median_seconds(
            lambda: mdm.sample(cond, lengths, guidance=mdm.default_guidance, sampler="ddim", steps=args["mdm_steps"]),
            repeats,
        ),
    }
    times["guidedmotion_total_s"] = times["guidedmotion_latent_s"] + times["guidedmotion_local_actions_s"]
    times["local_actions"] = len(graph.action_ids())
    times["threads"] = torch.get_num_threads()
    return times


def run_record(checkpoint: Path) -> dict | None:
    """run.json of the training run that wrote ``checkpoint`` (<run>/checkpoints/<file>), if there is one."""
    meta = checkpoint.resolve().parent.parent / "run.json"
    return json.loads(meta.read_text()) if meta.is_file() else None


def training_record(run: dict | None) -> dict:
    """What a stage's run.json says of its training: steps, wall seconds over all its sittings (the last sitting's
    where the run predates that record), precision and machine ("unknown" where it says nothing)."""
    run = run or {}
    config = (run.get("provenance") or {}).get("config") or {}
    machine = (run.get("provenance") or {}).get("machine")
    return {
        "steps": run.get("train_steps", "unknown"),
        "seconds": run.get("wall_seconds_all_sittings", run.get("train_seconds", "unknown")),
        "precision": (config.get("trainer") or {}).get("precision", "unknown"),
        "machine": machine_text(machine) if machine else "unknown",
    }


def machine_text(machine: dict) -> str:
    flags = "/".join(machine["flags"]) or "no AVX2/AVX-512 flag read"
    return f"{machine['cpu']}, {machine['cores']} cores, {machine['torch_threads']} torch threads, {flags}"


def training_lines(training: dict[str, dict]) -> list[str]:
    stages = [r["seconds"] for k, r in training.items() if k != "MDM"]
    guided = sum(stages) if all(isinstance(v, int | float) for v in stages) else None
    return [
        "### Training (wall seconds over all sittings; MDM trains for the GuidedMotion stages' sum)",
        "",
        "| stage | steps | seconds | precision | machine |",
        "|---|---:|---:|---|---|",
        *[f"| {k} | {r['steps']} | {r['seconds']} | {r['precision']} | {r['machine']} |" for k, r in training.items()],
        *([f"| GuidedMotion in all | | {guided:.1f} | | |"] if guided is not None else []),
        "",
    ]


def timing_lines(times: dict, meta: dict) -> list[str]:
    return [
        f"### Sampling time per motion ({times['frames']} frames, guidance on; median of {meta['timing_repeats']}; "
        f"{times['threads']} torch thread{'s' if times['threads'] > 1 else ''})",
        "",
        "| what | seconds |",
        "|---|---:|",
        f"| GuidedMotion latent sampling, {meta['level_steps_text']} level steps (50 in all) + VAE decoding | "
        f"{times['guidedmotion_latent_s']:.3f} |",
        f"| GuidedMotion local actions: {times['local_actions']} MDM motions (DDIM-{meta['mdm_steps']}, one batch) "
        f"+ action-VAE encoding | {times['guidedmotion_local_actions_s']:.3f} |",
        f"| GuidedMotion in all | {times['guidedmotion_total_s']:.3f} |",
        f"| MDM, DDIM-{meta['mdm_steps']} | {times['mdm_s']:.3f} |",
        "",
    ]


def write_timing(out: Path, times: dict, meta: dict) -> None:
    """``timing_only=true``: the sampling times alone, in <out>_timing.md/.json (the comparison files stay)."""
    out = out.with_name(out.name + "_timing")
    out.parent.mkdir(parents=True, exist_ok=True)
    lines = ["# GuidedMotion vs MDM: sampling time per motion", "", f"Latent model `{meta['latent']}`; MDM `{meta['mdm']}`.",
             "", *timing_lines(times, meta), f"Command: `{meta['command']}`", ""]  # fmt: skip
    write_markdown(out.with_suffix(".md"), "\n".join(lines))
    write_json(out.with_suffix(".json"), finite_or_null({**meta, "times": times}))


def write(out: Path, rows: dict, times: dict, meta: dict) -> None:
    out.parent.mkdir(parents=True, exist_ok=True)
    summaries = {name: summarise(reps) for name, reps in rows.items()}
    n = meta["replications"]
    main_rows = {k: summaries[k] for k in (list(ABLATION)[-1], meta["mdm_row"])}
    lines = [
        "# GuidedMotion vs MDM on the complex-motion test split",
        "",
        f"{meta['clips']} test sequences of `{meta['data']}` (2-3 joined real Bandai Namco clips each, >= 3 local "
        "actions, 150-196 frames; captions are **generated**). Evaluators: "
        f"`{meta['evaluators']}` (trained on this dataset). Mean ± 95% CI over {n} replications.",
        "",
        format_markdown(main_rows, "text", title="Evaluation"),
        format_markdown({k: summaries[k] for k in ABLATION}, "text", title="Ablation (paper Tab. 4 style)"),
        *training_lines(meta["training"]),
        *timing_lines(times, meta),
        f"Command: `{meta['command']}`",
        "",
    ]
    write_markdown(out.with_suffix(".md"), "\n".join(lines))
    payload = {**meta, "times": times, "summaries": {k: {m: list(v) for m, v in s.items()} for k, s in summaries.items()},
               "replications_raw": rows}  # fmt: skip
    write_json(out.with_suffix(".json"), finite_or_null(payload))


def main(argv: list[str] | None = None) -> int:
    from motiondiff.data.datamodules import PreparedDataModule  # lazy: lightning (+4.4 s to import)
    from motiondiff.eval.protocol import EvalClips, Evaluators  # lazy: torchmetrics (+2.6 s to import)
    from motiondiff.guided.local_actions import check_same_features  # lazy: spacy (+0.7 s to import)
    from motiondiff.pipelines.guided import GuidedMotionPipeline  # lazy: lightning, spacy (+5.1 s to import)
    from motiondiff.text.graph_features import graph_table  # lazy: spacy (+0.7 s to import)

    argv = list(sys.argv[1:] if argv is None else argv)
    cfg = study_config("guided_compare", argv)
    if len(cfg.level_steps) != 3:
        raise UsageError(f"level_steps must be three numbers [motion, action, specific], got {list(cfg.level_steps)}")
    latent_path = Path(cfg.latent)
    mdm_path = find_model(cfg.mdm, REPO_DIR / "outputs")
    latent = load_latent_model(latent_path)
    mdm = load_module(mdm_path)
    local_path = find_model(cfg.local_model or str(mdm_path), REPO_DIR / "outputs")
    local_mdm = mdm if local_path == mdm_path else load_module(local_path)
    check_same_features(local_mdm, latent)
    check_same_features(mdm, latent)
    pipe = GuidedMotionPipeline(latent, local_mdm, str(latent_path))
    settings = {
        "replications": cfg.replications,
        "level_steps": dict(zip(("motion", "action", "specific"), cfg.level_steps, strict=True)),
        "mdm_steps": cfg.mdm_steps,
        "local_frames": cfg.local_frames,
        "timing_repeats": cfg.timing_repeats,
        "seed": cfg.seed,
    }
    data = Path(cfg.data or REPO_DIR / "data" / "bandai_mini_compositional")
    dm = PreparedDataModule(data, max_frames=196)
    dm.setup("test")
    clips = EvalClips.from_dataset(dm.dataset("test"))
    evaluator_dir = Path(cfg.evaluators or REPO_DIR / "checkpoints" / "evaluators" / data.name)
    evaluators = Evaluators.load(evaluator_dir).for_module(mdm)
    table = graph_table([c for caps in clips.captions for c in caps], pipe.text_encoder)
    timing_only = cfg.timing_only
    rows: dict[str, list[dict]] = {}
    replications = 0 if timing_only else settings["replications"]
    for r in tqdm(range(replications), desc="replications", unit="replication", disable=timing_only):
        start = time.perf_counter()
        for name, metrics in replication(pipe, mdm, evaluators, clips, table, r, settings).items():
            rows.setdefault(name, []).append(metrics)
        tqdm.write(f"replication {r + 1}/{settings['replications']} in {time.perf_counter() - start:.0f} s")
    frames = int(clips.lengths.max())
    times = {"frames": frames, **sampling_times(pipe, mdm, table, clips.captions[0][0], frames, settings)}
    latent_run, mdm_run = run_record(latent_path), run_record(mdm_path)
    training = {f"GuidedMotion {level} VAE": training_record(run_record(Path(path)))
                for level, path in ((latent_run or {}).get("vaes") or {}).items()}  # fmt: skip
    training["GuidedMotion latent stage"] = training_record(latent_run)
    training["MDM"] = training_record(mdm_run)
    meta = {**settings, "latent": str(latent_path), "mdm": str(mdm_path), "local_model": str(local_path),
            "data": shown(data), "evaluators": shown(evaluator_dir),
            "clips": len(clips), "mdm_row": MDM_ROW.format(steps=settings["mdm_steps"]), "training": training,
            "level_steps_text": "/".join(str(v) for v in settings["level_steps"].values()),
            "command": "python -m motiondiff.studies.guided_compare " + " ".join(argv)}  # fmt: skip
    out = Path(cfg.out or DEFAULT_OUT)
    if timing_only:
        write_timing(out, times, meta)
        print(json.dumps(times, indent=1))
        return 0
    write(out, rows, times, meta)
    print(Path(out.with_suffix(".md")).read_text())
    return 0


if __name__ == "__main__":
    from motiondiff.runtime.scripting import user_errors

    sys.exit(user_errors(main)())
