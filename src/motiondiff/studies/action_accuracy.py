"""Does a text model do the action when people word the request their own way?

    python -m motiondiff.studies.action_accuracy [checkpoint=latest] [captions=paraphrases|<file.json>]
        [num_samples=10] [seed=0] [sampler=ddim steps=50 guidance=...] [out=<folder>]
        (every key and its default: conf/study/action_accuracy.yaml)

Generates `num_samples` motions for every description of a held-out descriptions file (default: the human-style
paraphrases of data/paraphrases/bandai_human.json, written before any model and kept out of training), each at the
median length of the real training clips of its action, classifies them with the dataset's action classifier and
writes the accuracy overall and per action (paraphrases.md, paraphrases_confusion.png, paraphrases.json).
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np
import torch
from tqdm import tqdm

from motiondiff.data.formats.prepared import load_split
from motiondiff.eval import action_table, report
from motiondiff.model_files.loading import load_model as load_module
from motiondiff.model_files.resolve import find_model
from motiondiff.pipelines.coverage import load_prompt_mapping
from motiondiff.runtime.atomic import finite_or_null, write_json
from motiondiff.runtime.paths import REPO_DIR, work_dir
from motiondiff.studies.behaviour import sampler_text, sampling_args
from motiondiff.studies.config import study_config

PARAPHRASES = REPO_DIR / "data" / "paraphrases" / "bandai_human.json"


def load_descriptions(spec: str) -> list[dict]:
    """[{"text", "action"}] of a descriptions file ("paraphrases": the project's held-out set)."""
    path = PARAPHRASES if spec == "paraphrases" else Path(spec)
    if not path.is_file():
        raise FileNotFoundError(f"captions={spec}: no file {path}; pass captions=paraphrases or a descriptions .json")
    items = json.loads(path.read_text())["descriptions"]
    if not items or not all(isinstance(d.get("text"), str) and d.get("action") for d in items):
        raise ValueError(f"{path}: every description needs a text and an action")
    return items


def action_lengths(data_root: Path, names: list[str], fps: float, max_frames: int) -> dict[str, int]:
    """Median frame count of each action's real training clips, within [2 s, the model's maximum]."""

    train = load_split(data_root, "train")
    lengths: dict[str, list[int]] = {}
    for i in range(train.num_clips):
        lengths.setdefault(train.label("content", i), []).append(int(train.arrays["lengths"][i]))
    low = int(2 * fps)
    return {n: int(np.clip(np.median(lengths.get(n, [4 * fps])), low, max_frames)) for n in names}


@torch.inference_mode()
def measure(module, evaluators, items: list[dict], lengths: dict[str, int], n: int, seed: int, **sampling) -> dict:
    """Classifier verdicts for n samples of every description: {"asked": [...], "predicted": [...], ...}."""
    from motiondiff.eval.protocol import generate  # lazy: torchmetrics (+2.6 s to import)

    names = evaluators.action_names
    unknown = sorted({d["action"] for d in items} - set(names))
    if unknown:
        raise ValueError(f"actions {unknown} are not among the classifier's: {names}")
    texts = [d["text"] for d in items for _ in range(n)]
    asked = [names.index(d["action"]) for d in items for _ in range(n)]
    frames = torch.tensor([lengths[d["action"]] for d in items for _ in range(n)])
    generator = torch.Generator().manual_seed(seed)
    with tqdm(total=len(texts), desc="descriptions", unit="motion") as bar:
        feats = generate(module, texts, frames, batch_size=128, generator=generator, progress=bar, **sampling)
    predicted = evaluators.embed_motion(feats)["action_logits"].argmax(-1).tolist()
    return {"texts": texts, "asked": asked, "predicted": predicted, "names": names}


def summarise(result: dict) -> tuple[float, list[dict]]:
    """Accuracy over all motions and one row per asked action (no real clips: the real column is NaN)."""
    asked, predicted = np.asarray(result["asked"]), np.asarray(result["predicted"])
    rows = action_table.per_action_rows(asked, [predicted], None, result["names"])
    return float((asked == predicted).mean()), rows


def main(argv: list[str]) -> None:
    import os

    from motiondiff.eval.protocol import Evaluators  # lazy: torchmetrics (+2.6 s to import)

    cfg = study_config("action_accuracy", argv)
    outputs = Path(os.environ.get("MOTIONDIFF_OUTPUT_DIR", work_dir() / "outputs"))
    ckpt = find_model(cfg.checkpoint, outputs)
    module = load_module(ckpt)
    if module.condition_kind != "text":
        raise SystemExit(f"{ckpt} is a {module.condition_kind} model; descriptions are for text models")
    module.prompt_mapping = load_prompt_mapping(ckpt, cfg.prompt_mapping)
    dataset = module.hparams.get("dataset") or "bandai_mini"
    evaluator_dir = Path(cfg.evaluators or REPO_DIR / "checkpoints" / "evaluators" / dataset)
    evaluators = Evaluators.load(evaluator_dir, module.hparams.num_joints)
    evaluators.for_module(module)
    items = load_descriptions(cfg.captions)
    sampling = sampling_args(cfg)
    sampling.setdefault("guidance", module.default_guidance)
    sampling.setdefault("smooth_sigma", module.default_smooth_sigma)
    n, seed = cfg.num_samples, cfg.seed
    names = evaluators.action_names
    lengths = action_lengths(Path(cfg.data or REPO_DIR / "data" / dataset), names, module.hparams.fps,
                             module.hparams.max_frames)  # fmt: skip
    start = time.perf_counter()
    result = measure(module, evaluators, items, lengths, n, seed, **sampling)
    accuracy, rows = summarise(result)
    out = Path(cfg.out or outputs / "action_accuracy" / time.strftime("%Y-%m-%d_%H-%M-%S"))
    out.mkdir(parents=True, exist_ok=True)
    notes = [f"checkpoint: {ckpt}", f"classifier: {evaluator_dir}", f"descriptions: {cfg.captions} ({len(items)}), "
             f"{n} samples each, seed {seed}; sampler {sampler_text(module, sampling)}, "
             f"guidance {sampling['guidance']:g}, prompt mapping {cfg.prompt_mapping}, temporal smoothing sigma {sampling['smooth_sigma'] or 'off'}; "
             f"{time.perf_counter() - start:.0f} s",
             f"accuracy over all {len(result['asked'])} motions: {accuracy:.3f}; lowest action: "
             f"{min(rows, key=lambda r: r['generated'])['action']} {min(r['generated'] for r in rows):.2f}",
             "clips = generated motions per action; the real column is empty (descriptions have no real clip)"]  # fmt: skip
    text = action_table.format_per_action(rows, "Action accuracy on held-out descriptions", notes)
    report.write_markdown(out / "paraphrases.md", text)
    write_json(out / "paraphrases.json", finite_or_null({"accuracy": accuracy, "rows": rows, **result}))
    action_table.plot_confusion(action_table.confusion(result["asked"], result["predicted"], len(names)), names,
                                out / "paraphrases_confusion.png", "held-out descriptions: asked vs classified")  # fmt: skip
    print(text)
    print(f"written to {out}")


if __name__ == "__main__":
    from motiondiff.runtime.scripting import user_errors

    user_errors(main)(sys.argv[1:])
