"""The evaluation protocol of `python evaluate.py` and of training's final evaluation (`train.py
final_evaluation=...`), shared by both commands: a model's metrics over N replications beside the Real row, written
as table.md, table.csv, metrics.json and an offline W&B run.

Every replication draws one caption per test clip, generates one motion per clip at its ground-truth length, and
computes the protocol's metrics (`motiondiff.eval.protocol`); MultiModality uses the first `mm_replications`. The
Real row treats the real test clips as the "generated" set and the real train clips as the reference, so it shows
what a perfect model would score.
"""

from __future__ import annotations

import logging
import time
from pathlib import Path

import numpy as np
import torch
from omegaconf import DictConfig
from tqdm import tqdm

from motiondiff import metrics as M
from motiondiff.cli.common import UsageError, apply_step_rules, sampling_steps, to_dict
from motiondiff.cli.outputs import smoothing_sigma
from motiondiff.edit.smoothing import SMOOTHABLE
from motiondiff.eval import action_table, official, report
from motiondiff.eval.protocol import (
    EvalClips,
    Evaluators,
    action_accuracy,
    generate,
    multimodality,
    replication_metrics,
)

log = logging.getLogger(__name__)
PROTOCOL = {"text": "text", "action": "action", "none": "unconstrained"}


def _conditions(kind: str, clips: EvalClips, captions: list[str]) -> list:
    return {"text": captions, "action": [int(a) for a in clips.actions]}.get(kind, [None] * len(clips))


# Datasets prepared from one source with one layout (features, labels): a model of one is evaluated on the other's
# clips (the embedded bandai_mini model on the full Bandai val split).
SAME_SOURCE = {"bandai_mini": "bandai", "bandai_mini_compositional": "bandai"}


def _source(dataset: str) -> str:
    return SAME_SOURCE.get(dataset, dataset)


def check_settings(cfg: DictConfig, module) -> tuple[float, int | None, float | None]:
    """(guidance, steps, smoothing sigma or None) as evaluated, after checking every setting."""
    guidance = module.default_guidance if cfg.guidance is None else float(cfg.guidance)
    if guidance < 0:
        raise UsageError(f"guidance must be >= 0, got {guidance}")
    steps = sampling_steps(cfg, module)
    if cfg.replications < 1 or cfg.mm_replications < 0:
        raise UsageError("replications must be >= 1 and mm_replications >= 0")
    trained_on = module.hparams.dataset
    if trained_on and _source(trained_on) != _source(cfg.dataset.name):
        raise UsageError(f"the checkpoint was trained on {trained_on!r}; pass dataset={trained_on}")
    sigma = smoothing_sigma(cfg, module)  # sample.py's rule: 0 off, null the model's default
    apply_step_rules(cfg, module)
    layout = (module.hparams.get("representation") or {}).get("name", "hml263")
    if sigma and layout not in SMOOTHABLE:
        raise UsageError(f"smooth_sigma needs a model of {'/'.join(SMOOTHABLE)} features (vvMDM filters positions); "
                         f"this one generates {layout}: evaluate with smooth_sigma=0")  # fmt: skip
    return guidance, steps, sigma


def load_evaluators(cfg: DictConfig, module, dm) -> Evaluators:
    """`evaluator=released`: the project's evaluators of the dataset (evaluator_dir); `evaluator=official`: the
    papers' own (motiondiff.eval.official, files under official_dir)."""
    try:
        if cfg.evaluator == "official":
            if not cfg.official_dir:
                raise UsageError(f"evaluator=official needs official_dir=<folder>, laid out as:\n{official.LAYOUT}")
            evaluators = official.official_evaluators(cfg.dataset.name, cfg.official_dir, module, dm)
        else:
            evaluators = Evaluators.load(cfg.evaluator_dir, num_joints=module.hparams.num_joints)
    except (FileNotFoundError, ValueError, KeyError) as err:
        raise UsageError(str(err).strip("'\"")) from None
    return evaluators.for_module(module)


def evaluate(
    cfg: DictConfig, module, evaluators: Evaluators, dm, checked: tuple[float, int | None, float | None]
) -> tuple[dict, dict, dict]:
    """(rows {"Real": summary, "Model": summary}, per-replication values, timings), with ``checked`` the
    (guidance, steps, sigma) from `check_settings`. Text models on labelled data also generate once per replication from
    each clip's label caption (`action_accuracy`, predictions kept in timings["action_predictions"]);
    `action_accuracy_random` scores the motions of the random captions."""
    guidance, steps, sigma = checked
    kind = module.condition_kind
    test = EvalClips.from_dataset(dm.dataset(cfg.split))
    if evaluators.meta.get("source") == "official" and evaluators.text_motion is not None:
        evaluators.text_motion.use_tokens(test.tokens)  # the official loader embeds the texts files' own tokens
    train = EvalClips.from_dataset(dm.dataset("train"))
    real_test, real_train = evaluators.embed_motion(test.features), evaluators.embed_motion(train.features)
    sampling = {"guidance": guidance, "sampler": cfg.sampler.name, "steps": steps, "eta": float(cfg.sampler.eta),
                "precision": cfg.precision, "smooth_sigma": sigma}  # fmt: skip
    common = {"diversity_pairs": cfg.diversity_pairs, "pool_size": cfg.pool_size, "knn_k": cfg.knn_k}
    reps: dict[str, list[dict]] = {"Real": [], "Model": []}
    own = kind == "none" and evaluators.bridge is not None  # vvMDM Fig. 2: smoothness of the model's own features too
    timings = {"generation_s": 0.0, "motions": 0}
    mm_n = min(cfg.mm_conditions, len(test))
    with_action = bool(cfg.action_accuracy) and evaluators.measures_action(kind, test)
    total = cfg.replications * len(test) * (2 if with_action else 1)
    total += min(cfg.mm_replications, cfg.replications) * mm_n * cfg.mm_repeats
    if with_action:
        real_accuracy = action_accuracy(evaluators, real_test, test.actions)
        timings["action_predictions"] = {"actions": test.actions.tolist(), "ids": test.ids, "model": [],
                                         "real": real_test["action_logits"].argmax(-1).tolist()}  # fmt: skip
    with tqdm(total=total if kind != "none" else cfg.replications * len(test), desc="generating", unit="motion") as bar:
        for r in range(cfg.replications):
            seed = int(cfg.seed) + r
            rng = np.random.default_rng(seed)
            captions = test.pick_captions(rng)
            text = evaluators.embed_text(captions) if kind == "text" else None
            reps["Real"].append(replication_metrics(kind, evaluators, real_train, real_test, text=text,
                                                    actions=test.actions, generated_features=evaluators.as_hml(test.features),
                                                    own_features=test.features if own else None,
                                                    seed=seed, **common))  # fmt: skip
            generator = torch.Generator(device=module.device).manual_seed(seed)
            start = time.perf_counter()
            feats = generate(module, _conditions(kind, test, captions), test.lengths, cfg.batch_size, generator,
                             progress=bar, **sampling)  # fmt: skip
            timings["generation_s"] += time.perf_counter() - start
            timings["motions"] += len(feats)
            generated = evaluators.embed_motion(feats)
            values = replication_metrics(kind, evaluators, real_test, generated, text=text,
                                         actions=test.actions, generated_features=evaluators.as_hml(feats), seed=seed,
                                         own_features=feats if own else None,
                                         **common)  # fmt: skip
            if kind == "action" and set(train.ids) != set(test.ids):  # MDM Tab. 4 (UESTC): FID against train too
                key = evaluators.fid_features(kind)
                values["fid_train"] = M.frechet_distance(*M.gaussian_statistics(real_train[key]),
                                                         *M.gaussian_statistics(generated[key]))  # fmt: skip
                reps["Real"][-1]["fid_train"] = reps["Real"][-1]["fid"]  # Real's FID is the one against train
            if with_action:
                reps["Real"][-1].update(action_accuracy=real_accuracy, action_accuracy_random=real_accuracy)
                values["action_accuracy_random"] = action_accuracy(evaluators, generated, test.actions)
                start = time.perf_counter()
                labelled = generate(module, test.label_captions(), test.lengths, cfg.batch_size, generator,
                                    progress=bar, **sampling)  # fmt: skip
                timings["generation_s"] += time.perf_counter() - start
                timings["motions"] += len(labelled)
                logits = evaluators.embed_motion(labelled)
                values["action_accuracy"] = action_accuracy(evaluators, logits, test.actions)
                timings["action_predictions"]["model"].append(logits["action_logits"].argmax(-1).tolist())
            if kind != "none" and r < cfg.mm_replications:
                values["multimodality"] = _multimodality(cfg, module, evaluators, test, captions, mm_n, seed,
                                                         bar, sampling, timings)  # fmt: skip
            reps["Model"].append(values)
    try:
        rows = {name: report.summarise(values) for name, values in reps.items()}
    except ValueError as err:  # a NaN or infinite metric (e.g. a degenerate covariance): one line, no table
        raise UsageError(f"{err}; nothing was written: look at the model's samples (sample.py), or evaluate more "
                         "motions per replication (a larger test split or replications=)") from None  # fmt: skip
    return rows, reps, timings


def _multimodality(cfg, module, evaluators, test, captions, n, seed, bar, sampling, timings) -> float:
    """Distances between motions generated repeatedly from the same caption/action (n conditions x repeats)."""
    rng = np.random.default_rng(seed)
    pick = np.sort(rng.choice(len(test), n, replace=False))
    conditions = [c for i in pick for c in [_conditions(module.condition_kind, test, captions)[i]] * cfg.mm_repeats]
    lengths = test.lengths[torch.as_tensor(pick)].repeat_interleave(cfg.mm_repeats)
    generator = torch.Generator(device=module.device).manual_seed(seed + 10_000)
    start = time.perf_counter()
    feats = generate(module, conditions, lengths, cfg.batch_size, generator, progress=bar, **sampling)
    timings["generation_s"] += time.perf_counter() - start
    timings["motions"] += len(feats)
    key = evaluators.fid_features(module.condition_kind)
    emb = evaluators.embed_motion(feats)[key].reshape(n, cfg.mm_repeats, -1)
    return multimodality(emb, cfg.mm_pairs, seed)


def _write_action_tables(out: Path, predictions: dict, evaluators: Evaluators, rows: dict, split: str) -> list[str]:
    """action_accuracy.md (per action, generated from label captions vs real) and action_confusion.png; returns
    the table's notes on the headline ratio."""
    names = evaluators.action_names
    gen, real = rows["Model"]["action_accuracy"][0], rows["Real"]["action_accuracy"][0]
    rand = rows["Model"]["action_accuracy_random"][0]
    notes = [
        f"action accuracy (the {split} clips' action classifier on motion generated from each clip's label caption): "
        f"{gen:.3f} against {real:.3f} on the real clips, ratio {gen / max(real, 1e-9):.2f}; from random captions "
        f"{rand:.3f} (ratio {rand / max(real, 1e-9):.2f}); per action: action_accuracy.md, action_confusion.png",
    ]
    asked = predictions["actions"]
    per_action = action_table.per_action_rows(asked, predictions["model"], predictions["real"], names)
    text = action_table.format_per_action(per_action, f"Action accuracy per action ({split}, label captions)", [
        f"generated: {len(predictions['model'])} replications pooled; real: the classifier on the real clips",
    ])  # fmt: skip
    report.write_markdown(out / "action_accuracy.md", text)
    gen_all = [a for _ in predictions["model"] for a in asked]
    matrix = action_table.confusion(gen_all, [p for rep in predictions["model"] for p in rep], len(names))
    action_table.plot_confusion(matrix, names, out / "action_confusion.png",
                                f"motion generated from label captions ({split})")  # fmt: skip
    print("\n" + text)
    return notes


def _log_wandb(out: Path, cfg: DictConfig, rows: dict, extra: dict) -> None:
    import wandb

    run = wandb.init(project="motiondiff", job_type="evaluate", dir=str(out), mode="offline",
                     config={"evaluate": to_dict(cfg), **extra}, reinit="finish_previous")  # fmt: skip
    for name, summary in rows.items():
        for metric, (mean, ci, n) in summary.items():
            run.summary[f"{name}/{metric}"] = mean
            run.summary[f"{name}/{metric}_ci95"] = ci
            run.summary[f"{name}/{metric}_n"] = n
    run.finish()


def report_evaluation(cfg: DictConfig, module, dm, out: Path, source: str) -> dict:
    """Evaluate `module` on `dm` with the evaluate.yaml settings in `cfg` and write table.md, table.csv and
    metrics.json (+ an offline W&B run) to `out`; returns the model's summary {metric: (mean, ci, n)}."""
    wall = time.perf_counter()
    checked = guidance, steps, sigma = check_settings(cfg, module)
    evaluators = load_evaluators(cfg, module, dm)
    if module.condition_kind == "text" and evaluators.text_motion is None:
        raise UsageError(f"{cfg.evaluator_dir} has no text_motion evaluator, which text models are evaluated with")
    rows, reps, timings = evaluate(cfg, module, evaluators, dm, checked)
    wall = time.perf_counter() - wall
    protocol = PROTOCOL[module.condition_kind]
    name = f"{module.hparams.dataset} {module.condition_kind} model"
    table = {"Real": rows["Real"], name: rows["Model"]}
    unconditioned = module.condition_kind == "none"  # no guidance, no R-precision: neither applies
    pools = "" if unconditioned else f"; R-precision pools of min({cfg.pool_size}, clips)"
    notes = [
        f"checkpoint: {source}",
        f"{cfg.replications} replications ({cfg.mm_replications} for MultiModality), mean ± 95% CI; "
        f"{len(EvalClips.from_dataset(dm.dataset(cfg.split)))} {cfg.split} clips{pools}",
        f"sampler {cfg.sampler.name}, steps {steps or 'default'}, "
        f"guidance {'none (unconditioned)' if unconditioned else f'{guidance:g}'}, temporal smoothing "
        f"sigma {sigma or 'off'}, safe x̂0 {module.clip_rule or 'none'}, timestep spacing "
        f"{module.timestep_spacing or 'sampler default'}, {cfg.precision}; "
        f"{timings['motions']} motions generated in {timings['generation_s']:.0f} s; whole evaluation {wall:.0f} s",
        f"Real: the real {cfg.split} clips scored against the real train clips",
    ]
    predictions = timings.pop("action_predictions", None)
    if predictions is not None:
        notes += _write_action_tables(out, predictions, evaluators, rows, cfg.split)
    text = report.format_markdown(table, protocol, title="Evaluation", notes=notes)
    report.write_markdown(out / "table.md", text)
    report.write_csv(out / "table.csv", table, protocol)
    extra = {"checkpoint": source, "real": {k: list(v) for k, v in rows["Real"].items()}, "wall_s": wall,
             "timings": timings, "sampler": to_dict(cfg.sampler), "steps": steps,
             "smooth_sigma": sigma, "clip_x0": module.clip_rule, "timestep_spacing": module.timestep_spacing, "replications": reps}  # fmt: skip
    report.write_summary_json(out / "metrics.json", guidance, rows["Model"], extra)
    if cfg.wandb:
        _log_wandb(out, cfg, table, {"checkpoint": source, "guidance": guidance})
    print("\n" + text)
    print(f"\nwritten to {out}")
    return rows["Model"]
