"""Foot sliding of generated motion before and after the foot-skate cleanup (`edit.foot_cleanup`, cleanup=feet).

    python -m motiondiff.studies.foot_cleanup [model=text] [text='a person walks forward'] [num_samples=8] ...
        (every key and its default: conf/study/foot_cleanup.yaml)

Generates `num_samples` motions of `text` with a released model (fixed seed), cleans each (as generated, and after
vvMDM's temporal filter for each `smooth_sigma`) and reports, per motion and on average: foot sliding (cm/s, mean horizontal speed of the contact joints during contact, on the contacts found
before the cleanup), the share of contact frames, how far the cleanup moved joints, that joints off the legs did not
move and that bone lengths did not change. The real clips of the embedded data are measured the same way, as the
level a clean motion has. Writes README.md and numbers.json to `out` (docs/results/foot_cleanup).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from tqdm import tqdm

from motiondiff.data.formats.prepared import load_split
from motiondiff.edit.foot_cleanup import clean_foot_skate, foot_sliding
from motiondiff.edit.smoothing import smooth_joints
from motiondiff.eval.report import write_markdown
from motiondiff.geometry.skeleton import Skeleton
from motiondiff.pipelines import MotionPipeline
from motiondiff.runtime.atomic import finite_or_null, write_json
from motiondiff.studies.config import study_config

OUT = Path(__file__).resolve().parents[3] / "docs" / "results" / "foot_cleanup"


def measure(joints: np.ndarray, skeleton: Skeleton, fps: float, keep: np.ndarray | None = None) -> dict:
    """What the cleanup does to one motion (N, J, 3): sliding before/after (cm/s; also on contacts found again in
    the cleaned motion), contact share, largest joint move, largest move of a joint off the legs and largest change
    of a bone's length (metres)."""
    result = clean_foot_skate(joints, skeleton, fps, keep=keep)
    legs = set(skeleton.part("legs"))
    others = [j for j in range(skeleton.num_joints) if j not in legs]
    parents = np.array(skeleton.parents)

    def bones(x):
        return np.linalg.norm(x[:, 1:] - x[:, parents[1:]], axis=-1)

    return {
        **result.summary(),
        "sliding_after_redetected_cm_s": foot_sliding(result.joints, skeleton, fps),
        "off_leg_max_shift_m": float(np.abs(result.joints[:, others] - joints[:, others]).max(initial=0.0)),
        "bone_length_max_change_m": float(np.abs(bones(result.joints) - bones(np.asarray(joints, float))).max()),
        "mean_leg_shift_m": float(np.linalg.norm(result.joints - joints, axis=-1)[:, sorted(legs)].mean()),
    }


def average(rows: list[dict]) -> dict:
    keys = [k for k in rows[0] if isinstance(rows[0][k], int | float)]
    return {k: float(np.mean([r[k] for r in rows])) for k in keys} | {
        "off_leg_max_shift_m": max(r["off_leg_max_shift_m"] for r in rows),
        "bone_length_max_change_m": max(r["bone_length_max_change_m"] for r in rows),
        "max_shift_m": max(r["max_shift_m"] for r in rows),
    }


def study(model: str, text: str, num_samples: int, seconds: float, seed: int, steps: int | None, split: str,
          smooth_sigmas=(0.0,)) -> dict:  # fmt: skip
    """The measures for each motion as generated (smooth_sigma 0) and after vvMDM's temporal filter of each sigma."""
    from motiondiff.data.datamodules import embedded_data_root  # lazy: lightning (+4.4 s to import)

    pipe = MotionPipeline.from_pretrained(model)
    out = pipe(text if pipe.condition_kind != "none" else None, seconds=seconds, num_samples=num_samples, seed=seed,
               steps=steps)  # fmt: skip
    clips = [c.joints for c in load_split(embedded_data_root(), split).clips() if len(c.joints) >= 3]
    same = clips and clips[0].shape[1] == out.skeleton.num_joints  # the embedded data's SMPL-22 joints
    settings = []
    with tqdm(total=len(smooth_sigmas) * len(out.joints) + (len(clips) if same else 0), desc="motions cleaned",
              unit="motion") as bar:  # fmt: skip

        def measured(j: np.ndarray) -> dict:
            row = measure(j, out.skeleton, out.fps)
            bar.update()
            return row

        for sigma in smooth_sigmas:
            joints = [smooth_joints(j, float(sigma)) if sigma else j for j in out.joints]
            rows = [measured(j) for j in joints]
            settings.append({"smooth_sigma": float(sigma), "generated": rows, "generated_mean": average(rows)})
        real = [measured(c) for c in clips] if same else []
    return {"model": model, "text": text, "seed": seed, "steps": out.info.get("steps"), "fps": out.fps,
            "num_samples": num_samples, "settings": settings, "real_split": split, "real_clips": len(real),
            "real_mean": average(real) if real else None}  # fmt: skip


def table(r: dict, command: str) -> str:
    real = r["real_mean"]
    lines = [
        "# Foot-skate cleanup (cleanup=feet): foot sliding before and after", "",
        f"{r['num_samples']} motions of \"{r['text']}\" from the released `{r['model']}` model (seed {r['seed']}, "
        f"DDIM-{r['steps']}, {r['fps']:g} fps), each cleaned by `motiondiff.edit.foot_cleanup.clean_foot_skate`. "
        "Sliding: mean horizontal speed of the contact joints (SMPL-22 ankles and toes) between consecutive contact "
        "frames, cm/s, on the contacts detected in the motion before the cleanup; \"re-detected\": on the contacts "
        "found again in the cleaned motion. Largest joint move: how far the cleanup moved any joint (knee, ankle or "
        "toe); unreachable: frames whose ankle target was beyond the straightened leg.",
    ]  # fmt: skip
    header = ["", "| motion | sliding before | after | after (re-detected) | contact frames | frames changed | "
              "largest joint move | unreachable frames |", "|---|---:|---:|---:|---:|---:|---:|---:|"]  # fmt: skip
    for setting in r["settings"]:
        sigma = setting["smooth_sigma"]
        title = "as generated (what sample.py writes)" if not sigma else f"after smooth_sigma={sigma:g} (vvMDM filter)"
        lines += ["", f"## {title}", *header]
        lines += [_row(str(i), m) for i, m in enumerate(setting["generated"])]
        lines.append(_row("**mean**", setting["generated_mean"]))
        if real:
            lines.append(_row(f"real {r['real_split']} clips ({r['real_clips']}), mean", real))
        g = setting["generated_mean"]
        lines += [
            "",
            f"No joint outside the legs moves (largest move {g['off_leg_max_shift_m']:.1e} m); a leg joint moves "
            f"{100 * g['mean_leg_shift_m']:.1f} cm on average; no bone changes length by more than "
            f"{g['bone_length_max_change_m']:.1e} m.",
        ]  # fmt: skip
    lines += ["", f"Command: `{command}`"]
    return "\n".join(lines) + "\n"


def _row(name: str, m: dict) -> str:
    return (f"| {name} | {m['sliding_before_cm_s']:.1f} | {m['sliding_after_cm_s']:.1f} | "
            f"{m['sliding_after_redetected_cm_s']:.1f} | {100 * m['contact_fraction']:.0f}% | {m['frames_changed']:.0f} "
            f"| {100 * m['max_shift_m']:.1f} cm | {m['unreachable_frames']:.0f} |")  # fmt: skip


def main(argv: list[str] | None = None) -> None:

    argv = sys.argv[1:] if argv is None else argv
    cfg = study_config("foot_cleanup", argv)
    out = Path(cfg.out or OUT)
    results = study(cfg.model, cfg.text, int(cfg.num_samples), float(cfg.seconds), int(cfg.seed), cfg.steps, cfg.split,
                    cfg.smooth_sigma)  # fmt: skip
    out.mkdir(parents=True, exist_ok=True)
    command = " ".join(["python -m motiondiff.studies.foot_cleanup", *argv])
    text = table(results, command)
    write_markdown(out / "README.md", text)
    write_json(out / "numbers.json", finite_or_null(results))
    print(text + f"\nwritten to {out}")


if __name__ == "__main__":
    from motiondiff.runtime.scripting import user_errors

    user_errors(main)()
