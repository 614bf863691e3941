"""Does the model do what the prompt says? The action classifier's verdict and measured facts of generated motion,
next to real clips of the asked action.

    python -m motiondiff.studies.behaviour [checkpoint=latest] [num_samples=10] [seed=0] [sampler=ddim steps=50]
        [guidance=2.5] [smooth_sigma=1.5] [out=<folder>]        (every key and its default: conf/study/behaviour.yaml)

For each prompt: how many samples the dataset's action classifier assigns the asked action (and what the rest
become), distance travelled, wrists above the head and mean joint speed, with the same facts for the real clips of
that label; a per-action table (behaviour.md) and a confusion matrix (behaviour_confusion.png) go to `out`. It
samples through the user-facing `MotionPipeline` with sample.py's default sampler (conf/sample.yaml), so the report
shows what users get.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch
from omegaconf import OmegaConf
from tqdm import tqdm

from motiondiff.data.formats.prepared import load_split
from motiondiff.data.preparing.captions import measure
from motiondiff.edit.measures import mean_joint_acceleration, mean_joint_speed
from motiondiff.edit.smoothing import smooth_features, smooth_joints
from motiondiff.eval import action_table
from motiondiff.lit.generation import generate_features, resolved_sampling
from motiondiff.model_files.loading import load_model as load_module
from motiondiff.model_files.resolve import find_model
from motiondiff.pipelines import MotionPipeline
from motiondiff.runtime.paths import CONF_DIR, REPO_DIR, work_dir
from motiondiff.studies.config import study_config

# prompt, seconds, dataset label of the real clips it should resemble
DEFAULT_PROMPTS = (
    ("a person walks forward", 4.0, "walk"),
    ("a person runs", 4.0, "run"),
    ("a person raises both hands", 3.0, "raise-up-both-hands"),
    ("a person waves the right hand", 3.0, "wave-right-hand"),
    ("a person kicks", 3.0, "kick"),
    ("a person bows", 3.0, "bow"),
    ("a person walks backwards", 4.0, "walk-back"),
)
# Walking speed must not depend on the asked length (issue 39): each prompt at each length, against the real clips'
SPEED_PROMPTS = (("a person walks forward", "walk"), ("a person runs", "run"))
SPEED_SECONDS = (2.0, 4.0, 6.0)
SPEED_TOLERANCE = 0.2  # generated median within ±20% of the real clips' median speed


def net_speed(joints: np.ndarray, fps: float) -> float:
    """Ground distance between the root's first and last position per second (m/s): jitter does not add to it."""
    path = joints[[0, -1], 0][:, [0, 2]]
    return float(np.linalg.norm(path[1] - path[0]) * fps / max(len(joints) - 1, 1))


def speed_table(pipe: MotionPipeline, data_root, n: int, seed: int, **sampling) -> list[dict]:
    """Median net speed of n samples per speed prompt and length, and of the real train clips of its label. An
    action-conditioned model is asked with the label instead of the text (labels it lacks are left out), as in
    `report`."""

    train = load_split(data_root, "train")
    rows = []
    prompts = SPEED_PROMPTS
    if pipe.condition_kind == "action":
        prompts = tuple((label, label) for _, label in prompts if label in pipe.actions)
    for prompt, label in tqdm(prompts, desc="speed by length", unit="prompt"):
        real = [net_speed(train.arrays["joints"][train.clip_slice(i)], pipe.fps) for i in range(train.num_clips)
                if train.label("content", i) == label]  # fmt: skip
        real_median = float(np.median(real)) if real else float("nan")
        for seconds in SPEED_SECONDS:
            if seconds > pipe.max_seconds:
                continue
            joints, _ = generate(pipe, prompt, seconds, n, seed, **sampling)
            speed = float(np.median([net_speed(j, pipe.fps) for j in joints]))
            ratio = speed / real_median if real else float("nan")
            rows.append({"prompt": prompt, "label": label, "seconds": seconds, "speed": speed, "real": real_median,
                         "ratio": ratio, "holds": bool(abs(ratio - 1) <= SPEED_TOLERANCE)})  # fmt: skip
    return rows


def speed_markdown(rows: list[dict]) -> str:
    lines = ["### Speed by length", "", f"Median net root speed of the samples (m/s) against the median of the real train "
             f"clips of the label; holds: within ±{SPEED_TOLERANCE:.0%}.", "",
             "| prompt | seconds | generated m/s | real m/s | ratio | holds |", "|---|---:|---:|---:|---:|---|"]  # fmt: skip
    for r in rows:
        lines.append(f"| {r['prompt']} | {r['seconds']:g} | {r['speed']:.2f} | {r['real']:.2f} | {r['ratio']:.2f} | "
                     f"{'yes' if r['holds'] else 'no'} |")  # fmt: skip
    return "\n".join(lines) + "\n"


def default_sampler(conf_dir: Path = CONF_DIR) -> dict:
    """sample.py's default sampler and steps, read from conf/sample.yaml and conf/sampler/<name>.yaml."""
    defaults = OmegaConf.to_container(OmegaConf.load(conf_dir / "sample.yaml").defaults)
    name = next(d["sampler"] for d in defaults if isinstance(d, dict) and "sampler" in d)
    sampler = OmegaConf.load(conf_dir / "sampler" / f"{name}.yaml")
    return {"sampler": str(sampler.name), "steps": sampler.get("steps")}


@dataclass
class Behaviour:
    travel: np.ndarray  # metres of root displacement on the ground, per sample
    both_wrists_up: np.ndarray  # bool: both wrists above the head for >= 0.3 s
    any_wrist_up: np.ndarray  # bool: either wrist above the head for >= 0.3 s
    speed: np.ndarray  # mean joint speed, m/s
    accel: np.ndarray  # mean joint acceleration, m/s^2: frame-to-frame jitter shows here first

    @classmethod
    def of(cls, clips: list[np.ndarray], fps: float) -> Behaviour:
        facts = [measure(j, fps) for j in clips]
        return cls(
            travel=np.array([f.distance for f in facts]),
            both_wrists_up=np.array([len(f.hands_above_head) == 2 for f in facts]),
            any_wrist_up=np.array([len(f.hands_above_head) > 0 for f in facts]),
            speed=np.array([mean_joint_speed(j, fps) for j in clips]),
            accel=np.array([mean_joint_acceleration(j, fps) for j in clips]),
        )

    def walk_success(self) -> np.ndarray:
        return (self.travel >= 1.5) & ~self.any_wrist_up

    def in_place(self) -> np.ndarray:
        return self.travel <= 0.5


def generate(
    pipe: MotionPipeline,
    prompt: str | None,
    seconds: float,
    n: int,
    seed: int,
    guidance: float | None = None,
    sampler: str = "ddim",
    steps: int | None = None,
    smooth_sigma: float | None = None,
) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """(joints (frames, J, 3), de-normalised features (frames, D)) of n motions for a prompt (None: unconditioned)
    through the pipeline, at most the model's length, with the model's default guidance unless given; ``smooth_sigma``
    > 0: vvMDM's temporal filter on the joints (the features are the model's, as generated)."""
    seconds = min(seconds, pipe.max_seconds)
    if prompt is None and pipe.condition_kind != "none":  # the pipeline asks conditioned models with a condition
        joints, feats = _unconditioned(pipe, seconds, n, seed, sampler, steps, smooth_sigma)
    else:
        out = pipe(prompt if pipe.condition_kind != "none" else None, seconds=seconds, num_samples=n,
                   guidance=guidance, sampler=sampler, steps=steps, seed=seed, smooth_sigma=smooth_sigma)  # fmt: skip
        joints, feats = out.joints, out.features
    return joints, feats


def _unconditioned(pipe, seconds, n, seed, sampler, steps, smooth_sigma) -> tuple[list, list]:
    """A conditioned model's samples of its ∅ condition (classifier-free guidance's unconditional half), made and
    decoded as the pipeline makes its motions."""

    model = pipe.model
    frames = torch.full((n,), round(seconds * pipe.fps))
    sampler, steps = resolved_sampling(model, sampler, steps)
    generator = torch.Generator(device=model.device).manual_seed(int(seed))
    feats = generate_features(model, [None] * n, frames, generator=generator, sampler=sampler, steps=steps)
    joints = [smooth_joints(model.representation.decode_numpy(f).astype(np.float32), smooth_sigma) for f in feats]
    return joints, feats


def real_clips(root, label: str, max_frames: int, splits=("train", "val", "test")) -> list[np.ndarray]:
    """Canonical joints (first `max_frames`) of the real clips with this content label."""

    clips = []
    for split in splits:
        data = load_split(root, split)
        for i in range(data.num_clips):
            if data.label("content", i) == label:
                clips.append(data.arrays["joints"][data.clip_slice(i)][:max_frames])
    return clips


def sampling_args(cfg) -> dict:
    """sampler, steps, guidance, smooth_sigma of a study's config over sample.py's default sampler (sampler: null);
    guidance and smooth_sigma only where given (smooth_sigma 0: off)."""
    sampling = default_sampler() if cfg.sampler is None else {"sampler": cfg.sampler, "steps": None}
    if cfg.steps is not None:
        sampling["steps"] = cfg.steps
    if cfg.guidance is not None:
        sampling["guidance"] = cfg.guidance
    if cfg.smooth_sigma is not None:
        sampling["smooth_sigma"] = cfg.smooth_sigma or None
    return sampling


def sampler_text(module, sampling: dict) -> str:
    """'<sampler> <steps> steps' that actually ran for a study's `sampling` (the model's own sampler and its steps
    where the config named none), for the report's header."""
    name, steps = resolved_sampling(module, sampling["sampler"], sampling["steps"])
    return f"{name}, {steps or 'all'} steps"


def classify(evaluators, features: list[np.ndarray], smooth_sigma: float | None = None, layout: str = "hml263"):
    """The action classifier's label id for each clip of features, smoothed first as evaluate.py scores samples
    (``smooth_features``: the classifier reads the motion whose joints the report measures)."""

    features = [smooth_features(f, smooth_sigma, layout) for f in features]
    return evaluators.embed_motion(features)["action_logits"].argmax(-1)


def report(module, data_root, n: int = 10, seed: int = 0, evaluators=None, prompts=DEFAULT_PROMPTS, **sampling) -> dict:
    """{prompt: {"label", "generated": Behaviour, "real": Behaviour, "predicted": names or None}} + unconditioned.
    An action-conditioned model is asked with each prompt's label instead of its text (labels it lacks are left
    out), so both kinds of model are measured on the same actions."""
    fps = module.hparams.fps
    pipe = MotionPipeline(module)
    layout = getattr(getattr(module, "representation", None), "name", "hml263")
    names = evaluators.action_names if evaluators is not None and evaluators.action else None
    if module.condition_kind == "action":
        known = set(module.hparams.action_names)
        prompts = tuple((label, seconds, label) for _, seconds, label in prompts if label in known)
    rows = {}
    for prompt, seconds, label in tqdm(prompts, desc="behaviour", unit="prompt"):
        frames = round(seconds * fps)
        joints, feats = generate(pipe, prompt, seconds, n, seed, **sampling)
        real = real_clips(data_root, label, frames)
        predicted = classify(evaluators, feats, sampling.get("smooth_sigma"), layout) if names else None
        rows[prompt] = {
            "label": label,
            "generated": Behaviour.of(joints, fps),
            "real": Behaviour.of(real, fps) if real else None,
            "predicted": None if predicted is None else [names[i] for i in predicted],
        }
    if module.condition_kind == "text":
        uncond, _ = generate(pipe, None, 4.0, n, seed, **sampling)
        rows["(unconditioned)"] = {"label": None, "generated": Behaviour.of(uncond, fps), "real": None,
                                   "predicted": None}  # fmt: skip
    return rows


def print_report(rows: dict) -> None:
    """Counts per prompt; "walk ok" = travelled >= 1.5 m with no wrist above the head; "as asked" = samples the
    action classifier assigns the prompt's label."""
    print(f"{'prompt':<31}{'who':>10}{'n':>4}{'as asked':>9}{'travel m':>9}{'travel>=1.5m':>13}{'walk ok':>8}"
          f"{'travel<=0.5m':>13}{'2 wrists up':>12}{'no wrist up':>12}{'speed m/s':>10}{'acc m/s2':>9}")  # fmt: skip
    for prompt, row in rows.items():
        for who in ("generated", "real"):
            b = row.get(who)
            if b is None:
                continue
            k = len(b.travel)
            asked = "" if who == "real" or row["predicted"] is None else str(row["predicted"].count(row["label"]))
            print(f"{prompt:<31}{who:>10}{k:>4}{asked:>9}{np.median(b.travel):>9.2f}{int((b.travel >= 1.5).sum()):>13}"
                  f"{int(b.walk_success().sum()):>8}{int(b.in_place().sum()):>13}"
                  f"{int(b.both_wrists_up.sum()):>12}{int((~b.any_wrist_up).sum()):>12}{b.speed.mean():>10.2f}"
                  f"{b.accel.mean():>9.1f}")  # fmt: skip


def markdown_report(rows: dict, header: list[str]) -> str:
    """behaviour.md: per prompt, the classifier's verdicts and travel/speed next to the real clips'."""
    lines = ["### Behaviour report", "", *[f"- {h}" for h in header], "",
             "| prompt | asked action | classified as asked | classified as (others) | median travel m (real) "
             "| mean joint speed m/s (real) | mean joint acceleration m/s² (real) |", "|---|---|---:|---|---:|---:|---:|"]  # fmt: skip
    for prompt, row in rows.items():
        if row["label"] is None:
            continue
        gen, real, pred = row["generated"], row["real"], row["predicted"] or []
        others = {p: pred.count(p) for p in dict.fromkeys(pred) if p != row["label"]}
        other_text = ", ".join(f"{p} {c}" for p, c in sorted(others.items(), key=lambda x: -x[1]))
        real_travel = f" ({np.median(real.travel):.2f})" if real is not None else " (no real clip)"
        real_speed = f" ({real.speed.mean():.2f})" if real is not None else ""
        real_accel = f" ({real.accel.mean():.1f})" if real is not None else ""
        lines.append(f"| {prompt} | {row['label']} | {pred.count(row['label'])} of {len(gen.travel)} | {other_text} | "
                     f"{np.median(gen.travel):.2f}{real_travel} | {gen.speed.mean():.2f}{real_speed} | "
                     f"{gen.accel.mean():.1f}{real_accel} |")  # fmt: skip
    return "\n".join(lines) + "\n"


def main(argv: list[str]) -> None:
    import os
    import time

    from motiondiff.eval.protocol import Evaluators  # lazy: torchmetrics (+2.6 s to import)

    cfg = study_config("behaviour", argv)
    outputs = Path(os.environ.get("MOTIONDIFF_OUTPUT_DIR", work_dir() / "outputs"))
    ckpt = find_model(cfg.checkpoint, outputs)
    module = load_module(ckpt)
    dataset = module.hparams.get("dataset") or "bandai_mini"
    data_root = cfg.data or str(REPO_DIR / "data" / dataset)
    evaluator_dir = Path(cfg.evaluators or REPO_DIR / "checkpoints" / "evaluators" / dataset)
    evaluators = Evaluators.load(evaluator_dir, module.hparams.num_joints).for_module(module) if any(
        evaluator_dir.glob("action.safetensors")) else None  # fmt: skip
    sampling = sampling_args(cfg)
    sampling.setdefault("smooth_sigma", module.default_smooth_sigma)  # what sample.py gives users by default
    guidance = sampling.get("guidance", module.default_guidance)
    header = [f"checkpoint: {ckpt}", f"sampler: {sampler_text(module, sampling)}, "
              f"guidance {guidance:g}, temporal smoothing sigma {sampling['smooth_sigma'] or 'off'}, "
              f"seed {cfg.seed}",
              f"classifier: {evaluator_dir if evaluators else 'none (no action.safetensors): no verdicts'}"]  # fmt: skip
    print("\n".join(header))
    rows = report(module, data_root, cfg.num_samples, cfg.seed, evaluators, **sampling)
    print_report(rows)
    speeds = speed_table(MotionPipeline(module), data_root, cfg.num_samples, cfg.seed, **sampling) if (
        module.condition_kind in ("text", "action")) else []  # fmt: skip
    out = Path(cfg.out or outputs / "behaviour" / time.strftime("%Y-%m-%d_%H-%M-%S"))
    out.mkdir(parents=True, exist_ok=True)
    speed_text = speed_markdown(speeds) if speeds else ""
    print(speed_text)
    (out / "behaviour.md").write_text(markdown_report(rows, header) + ("\n" + speed_text if speed_text else ""))
    if evaluators is not None:
        names = evaluators.action_names
        asked = [names.index(r["label"]) for r in rows.values() if r["predicted"] and r["label"] in names
                 for _ in r["predicted"]]  # fmt: skip
        got = [names.index(p) for r in rows.values() if r["predicted"] and r["label"] in names for p in r["predicted"]]
        action_table.plot_confusion(action_table.confusion(asked, got, len(names)), names,
                                    out / "behaviour_confusion.png", "behaviour prompts: asked vs classified")  # fmt: skip
    print(f"written to {out}")


if __name__ == "__main__":
    from motiondiff.runtime.scripting import user_errors

    user_errors(main)(sys.argv[1:])
