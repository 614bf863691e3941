"""Build a text release's prompt-coverage bank and choose its warning threshold.

    python -m motiondiff.studies.prompt_coverage checkpoint=<release> [data=data/bandai] [per_action=128]
        (every key and its default: conf/study/prompt_coverage.yaml)

The bank (`motiondiff.text.coverage`) holds the model's text features of at most `per_action` distinct training
captions per action. The threshold follows docs/results/coverage/rules.md: the value that best separates the val
split's captions (in-domain) from hand-written out-of-domain prompts, by balanced accuracy. Writes the bank beside the
release and a report (coverage.md, coverage.json, a histogram); the held-out human-style sets' warning rates are
reported after the choice, never used for it.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from motiondiff.data.formats.prepared import load_split
from motiondiff.data.mirror import swap_left_right
from motiondiff.lit.conditions import text_encoder_kwargs
from motiondiff.model_files.loading import load_model
from motiondiff.model_files.resolve import find_model
from motiondiff.runtime.atomic import write_json
from motiondiff.runtime.paths import REPO_DIR, shown, work_dir
from motiondiff.studies.config import study_config
from motiondiff.text.coverage import build_coverage, choose_threshold, coverage_path
from motiondiff.text.encoders import build_text_encoder

OUT_OF_DOMAIN = REPO_DIR / "data" / "coverage" / "out_of_domain.json"
HELD_OUT = {"bandai_human": REPO_DIR / "data" / "paraphrases" / "bandai_human.json",
            "bandai_human_2": REPO_DIR / "data" / "paraphrases" / "bandai_human_2.json"}  # fmt: skip
EXAMPLES = ["a person walks forward", "a person jumps forward", "a person runs", "a person does a cartwheel"]


def split_captions(data_root: Path, split: str, mirror: bool) -> dict[str, list[str]]:
    """Captions of a prepared split by action name (with their mirror images' when `mirror`)."""

    data = load_split(data_root, split)
    names = list(data.meta["labels"]["content"])
    by_action: dict[str, list[str]] = {}
    for rec in data.records():
        by_action.setdefault(names[rec.action], []).extend(rec.texts)
        if mirror:
            by_action.setdefault(swap_left_right(names[rec.action]), []).extend(swap_left_right(t) for t in rec.texts)
    return by_action


def main(argv: list[str]) -> None:
    import os

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cfg = study_config("prompt_coverage", argv)
    outputs = Path(os.environ.get("MOTIONDIFF_OUTPUT_DIR", work_dir() / "outputs"))
    release = find_model(cfg.checkpoint, outputs)
    if release.suffix == ".ckpt":
        raise SystemExit(f"{release}: a coverage bank belongs beside a release; release the checkpoint first")
    module = load_model(release)
    if module.condition_kind != "text":
        raise SystemExit(f"{release} is a {module.condition_kind} model; coverage is for text models")
    hp = module.hparams
    mirror = bool(cfg.mirror)
    data_root = Path(cfg.data or REPO_DIR / "data" / (hp.get("dataset") or "bandai"))
    kwargs = text_encoder_kwargs(hp.text_encoder)
    encoder = build_text_encoder(**kwargs)

    def encode(texts: list[str]) -> np.ndarray:
        return encoder.encode(list(texts)).float().cpu().numpy()

    bank = build_coverage(split_captions(data_root, "train", mirror), encode, threshold=0.0,
                          encoder=kwargs.get("name", ""), per_action=int(cfg.per_action), seed=int(cfg.seed))  # fmt: skip
    val = sorted({t for texts in split_captions(data_root, "val", False).values() for t in texts})
    ood = json.loads(Path(cfg.out_of_domain or OUT_OF_DOMAIN).read_text())["texts"]
    val_best, ood_best = bank.best(encode(val)), bank.best(encode(ood))
    threshold, balanced = choose_threshold(val_best, ood_best)
    bank = type(bank)(bank.features, bank.actions, bank.action_names, threshold, bank.encoder)
    saved = bank.save(coverage_path(release))

    out = Path(cfg.out or REPO_DIR / "docs" / "results" / "coverage" / release.name.split(".")[0])
    out.mkdir(parents=True, exist_ok=True)
    lines = [f"# Prompt coverage of `{release.name}`", "",
             f"Bank: {len(bank.features)} distinct training captions ({cfg.per_action} at most per action, seed "
             f"{cfg.seed}, mirrored captions {'included' if mirror else 'not included'}) from {shown(data_root)}; "
             f"written to `{shown(saved)}`.", "",
             "Chosen by the rule of [rules.md](../rules.md):", "",
             "| side | texts | warned (below the threshold) | median best similarity |", "|---|---:|---:|---:|",
             f"| val captions (in-domain, generated) | {len(val)} | {np.mean(val_best < threshold):.3f} | "
             f"{np.median(val_best):.3f} |",
             f"| out-of-domain prompts | {len(ood)} | {np.mean(ood_best < threshold):.3f} | {np.median(ood_best):.3f} |",
             "", f"**Threshold {threshold:.3f}** (balanced accuracy {balanced:.3f}).", "",
             "Reported after the choice, not used for it:", "",
             "| set | texts | warned | median best similarity |", "|---|---:|---:|---:|"]  # fmt: skip
    held = {}
    for name, path in HELD_OUT.items():
        texts = [d["text"] for d in json.loads(path.read_text())["descriptions"]]
        best = bank.best(encode(texts))
        held[name] = {"n": len(texts), "warned": float(np.mean(best < threshold)), "median": float(np.median(best))}
        lines.append(f"| {name} (held-out human-style) | {len(texts)} | {held[name]['warned']:.3f} | "
                     f"{held[name]['median']:.3f} |")  # fmt: skip
    lines += ["", "| prompt | best similarity | warns | nearest actions |", "|---|---:|---|---|"]
    for report in bank.check(EXAMPLES, encode(EXAMPLES)):
        near = ", ".join(f"{n} {s:.2f}" for n, s in report.nearest)
        lines.append(f"| {report.prompt} | {report.similarity:.3f} | {'yes' if report.far else 'no'} | {near} |")
    ood_reports = bank.check(ood, encode(ood))
    lines += ["", "Out-of-domain prompts that do not warn:", ""]
    lines += [f"- {r.prompt} ({r.similarity:.3f}, nearest {r.nearest[0][0]})" for r in ood_reports if not r.far] or [
        "- none"
    ]
    (out / "coverage.md").write_text("\n".join(lines) + "\n")
    write_json(out / "coverage.json", {"threshold": threshold, "balanced_accuracy": balanced, "bank": len(bank.features),
                                       "val": val_best.tolist(), "out_of_domain": ood_best.tolist(), "held_out": held})  # fmt: skip
    fig, ax = plt.subplots(figsize=(6, 3.2))
    bins = np.linspace(min(val_best.min(), ood_best.min()), 1.0, 40)
    ax.hist(val_best, bins, alpha=0.6, density=True, label=f"val captions ({len(val)})")
    ax.hist(ood_best, bins, alpha=0.6, density=True, label=f"out-of-domain ({len(ood)})")
    ax.axvline(threshold, color="k", ls="--", label=f"threshold {threshold:.2f}")
    ax.set_xlabel("largest cosine similarity to the coverage bank")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "coverage.png", dpi=110)
    print("\n".join(lines))


if __name__ == "__main__":
    from motiondiff.runtime.scripting import user_errors

    user_errors(main)(sys.argv[1:])
