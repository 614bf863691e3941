"""Does the model do what the prompt says? Measured facts of generated motion next to real clips.

    python -m motiondiff.eval.behaviour [checkpoint=latest] [num_samples=10] [seed=0]

For each prompt: distance travelled, wrists above the head, mean joint speed over N samples, and the same facts
for the real test/val clips of the matching label, so a sanity check of a trained model is one command.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass

import numpy as np
import torch

from motiondiff.data.captions import measure
from motiondiff.data.features import joints_from_features

# prompt, seconds, dataset label of the real clips it should resemble, what "success" means
DEFAULT_PROMPTS = (
    ("a person walks forward", 4.0, "walk"),
    ("a person raises both hands", 2.5, "raise-up-both-hands"),
)


@dataclass
class Behaviour:
    travel: np.ndarray  # metres of root displacement on the ground, per sample
    both_wrists_up: np.ndarray  # bool: both wrists above the head for >= 0.3 s
    any_wrist_up: np.ndarray  # bool: either wrist above the head for >= 0.3 s
    speed: np.ndarray  # mean joint speed, m/s

    @classmethod
    def of(cls, clips: list[np.ndarray], fps: float) -> Behaviour:
        facts = [measure(j, fps) for j in clips]
        return cls(
            travel=np.array([f.distance for f in facts]),
            both_wrists_up=np.array([len(f.hands_above_head) == 2 for f in facts]),
            any_wrist_up=np.array([len(f.hands_above_head) > 0 for f in facts]),
            speed=np.array([mean_joint_speed(j, fps) for j in clips]),
        )

    def walk_success(self) -> np.ndarray:
        return (self.travel >= 1.5) & ~self.any_wrist_up

    def in_place(self) -> np.ndarray:
        return self.travel <= 0.5


def mean_joint_speed(joints: np.ndarray, fps: float) -> float:
    return float(np.linalg.norm(np.diff(joints, axis=0), axis=-1).mean() * fps)


def generate(
    module,
    prompt: str | None,
    seconds: float,
    n: int,
    seed: int,
    guidance: float | None = None,
    sampler: str = "ddpm",
    steps: int | None = None,
):
    """n joint sequences (frames, 22, 3) for a prompt (None: unconditioned); MDM's sampler and the model's
    default guidance unless given."""
    from motiondiff.cli.sample import make_condition

    frames = min(round(seconds * module.hparams.fps), module.hparams.max_frames)
    gen = torch.Generator().manual_seed(seed)
    guidance = module.default_guidance if guidance is None else guidance
    cond = make_condition(module, prompt, n) if prompt is not None else None
    feats = module.sample(
        cond, torch.full((n,), frames), guidance=guidance, sampler=sampler, steps=steps, generator=gen, progress=True
    )
    return [joints_from_features(f) for f in module.denormalise(feats).cpu().numpy()]


def real_clips(root, label: str, max_frames: int, splits=("train", "val", "test")) -> list[np.ndarray]:
    """Canonical joints (first `max_frames`) of the real clips with this content label."""
    from motiondiff.data.prepared import load_split

    clips = []
    for split in splits:
        data = load_split(root, split)
        for i in range(data.num_clips):
            if data.label("content", i) == label:
                clips.append(data.arrays["joints"][data.clip_slice(i)][:max_frames])
    return clips


def report(module, data_root, n: int = 10, seed: int = 0, **sampling) -> dict:
    fps = module.hparams.fps
    rows = {}
    for prompt, seconds, label in DEFAULT_PROMPTS:
        frames = round(seconds * fps)
        gen = Behaviour.of(generate(module, prompt, seconds, n, seed, **sampling), fps)
        real = Behaviour.of(real_clips(data_root, label, frames), fps)
        rows[prompt] = {"generated": gen, "real": real}
    uncond = generate(module, None, 4.0, n, seed, **sampling)
    rows["(unconditioned)"] = {"generated": Behaviour.of(uncond, fps), "real": None}
    return rows


def print_report(rows: dict) -> None:
    """Counts per prompt; "walk ok" = travelled >= 1.5 m with no wrist above the head."""
    print(f"{'prompt':<28}{'who':>10}{'n':>4}{'travel>=1.5m':>14}{'walk ok':>9}{'travel<=0.5m':>14}{'2 wrists up':>13}"
          f"{'no wrist up':>13}{'speed m/s':>11}")  # fmt: skip
    for prompt, pair in rows.items():
        for who, b in pair.items():
            if b is None:
                continue
            k = len(b.travel)
            print(f"{prompt:<28}{who:>10}{k:>4}{int((b.travel >= 1.5).sum()):>14}{int(b.walk_success().sum()):>9}"
                  f"{int(b.in_place().sum()):>14}"
                  f"{int(b.both_wrists_up.sum()):>13}{int((~b.any_wrist_up).sum()):>13}{b.speed.mean():>11.2f}")  # fmt: skip


def main(argv: list[str]) -> None:
    import os

    from motiondiff.cli.common import REPO_DIR, find_checkpoint
    from motiondiff.cli.sample import load_module

    args = dict(a.split("=", 1) for a in argv)
    outputs = os.environ.get("MOTIONDIFF_OUTPUT_DIR", REPO_DIR / "outputs")
    ckpt = find_checkpoint(args.get("checkpoint", "latest"), outputs)
    module = load_module(ckpt)
    print(
        f"checkpoint: {ckpt}  sampler: {args.get('sampler', 'ddpm')}  guidance: {args.get('guidance', module.default_guidance)}"
    )
    data_root = args.get("data", str(REPO_DIR / "data" / "bandai_mini"))
    sampling = {"sampler": args.get("sampler", "ddpm"), "steps": int(args["steps"]) if "steps" in args else None}
    if "guidance" in args:
        sampling["guidance"] = float(args["guidance"])
    print_report(report(module, data_root, int(args.get("num_samples", 10)), int(args.get("seed", 0)), **sampling))


if __name__ == "__main__":
    main(sys.argv[1:])
