"""One continuous motion from several timed conditions, longer than the model's max_frames, by prefix in-painting.

    walk forward (4 s) | wave (3 s) | walk back (4 s)   ->   one 11 s motion

Window 1 is sampled freely. Every later window is ``overlap + new`` frames long: it starts with the last ``overlap``
frames generated so far, the first ``overlap − blend`` of them held by in-painting (``edit.inpaint``, exact on the
mask), and the model generates the rest under the window's own condition. A condition longer than one window allows
(max_frames − overlap new frames) is split into several windows of near-equal length.

Stitching. The held frames are the same motion in both copies (in-painting returns them exactly), so the window's
copy is dropped. With ``blend = 0`` every frame of the result is kept or generated right after the kept ones, in one
window. A model that has not learnt to continue the held frames smoothly jumps at the first frame it generates (it
switches to the new prompt in one step); ``blend = b`` frames let it regenerate the last b overlap frames and
cross-fade them in, x_i ← (1 − w_i) x_i^before + w_i x_i^window with w_i = i/(b+1), i = 1..b, which spreads that
jump over b+1 steps (linear in the features: positions for jp, 6D columns / quaternions / matrices for rp*jr, which
the decoders re-orthonormalise, and hml263 rows).

Placement: the model was trained on canonical clips (root at the x,z origin facing +Z at frame 0). hml263/kit251
features are the same wherever the motion stands, so the overlap rows are copied as they are and the stitched rows
decode as one motion. For jp and rp*jr the overlap is first turned and shifted so that its first frame is canonical,
and the new window turned back to where the overlap stood (``edit.canonical``).

Boundary report: at each seam (first new frame s of a window) the speed of the step s−1 → s,
v_seam = (fps / J) Σ_j |x_{s,j} − x_{s−1,j}|, over the median of the same per-step speed over the whole motion;
≈ 1 is a seamless join, a pop shows as a ratio of several. With blending, every step the stitch touched (s−b−1 → s−b
up to s−1 → s) is looked at and the fastest one reported, so a cross-fade cannot hide a jump where it starts.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from itertools import pairwise
from typing import Any

import numpy as np
import torch

from motiondiff.edit.canonical import from_canonical, placement, to_canonical
from motiondiff.edit.inpaint import EDIT_MODES, SamplingOptions, inpaint
from motiondiff.edit.smoothing import smooth_joints
from motiondiff.lit.generation import check_finite_output
from motiondiff.runtime.errors import UsageError


@dataclass(frozen=True)
class WindowPlan:
    """One model call: frames [start − overlap, end) of the long motion; the first ``overlap − blend`` are held,
    the next ``blend`` regenerated and cross-faded into the motion before."""

    segment: int  # index of the condition it generates for
    start: int  # first new frame (in the long motion)
    end: int  # one past the last new frame
    overlap: int  # frames taken from the motion before (0 for the first window)
    blend: int = 0  # of which the last ones are cross-faded rather than held

    @property
    def held(self) -> int:
        return self.overlap - self.blend

    @property
    def length(self) -> int:
        return self.overlap + self.end - self.start


@dataclass
class Window:
    plan: WindowPlan
    features: np.ndarray  # (B, length, D) de-normalised, canonical placement: generated, held and blended frames
    yaw: np.ndarray  # (B,) placement of the window in the long motion: p_world = R_y(yaw) p + offset
    offset: np.ndarray  # (B, 3)


@dataclass
class LongMotion:
    features: np.ndarray  # (B, T, D) de-normalised (world placement for jp / rp*jr)
    joints: np.ndarray  # (B, T, J, 3) decoded, metres
    fps: float
    segments: list[dict]  # per condition: label, seconds, start, end (frames of the long motion)
    windows: list[Window]
    boundaries: list[list[dict]] = field(default_factory=list)  # per sample, per seam: see boundary_report

    @property
    def num_frames(self) -> int:
        return self.features.shape[1]


def plan_windows(segment_frames: Sequence[int], overlap: int, max_frames: int, blend: int = 0) -> list[WindowPlan]:
    """Windows covering the segments back to back. Every window holds ≤ max_frames frames; a segment of F frames
    needs ⌈F / (max_frames − overlap)⌉ windows of near-equal length (the first window of the motion has no overlap
    but is split by the same rule, so pieces of one condition stay alike). At least one overlap frame stays held."""
    if not 1 <= overlap < max_frames:
        raise ValueError(f"the overlap must be 1 to {max_frames - 1} frames (the model's max_frames is {max_frames})")
    if not 0 <= blend < overlap:
        raise ValueError(f"the blend must be 0 to {overlap - 1} frames: shorter than the {overlap}-frame overlap")
    plans, start = [], 0
    for k, frames in enumerate(segment_frames):
        if frames < 1:
            raise ValueError(f"segment {k + 1} has {frames} frames; every segment needs at least one")
        pieces = math.ceil(frames / (max_frames - overlap))
        for size in np.diff(np.linspace(0, frames, pieces + 1).round().astype(int)):
            taken = min(overlap, start)
            plans.append(WindowPlan(k, start, start + int(size), taken, min(blend, max(taken - 1, 0))))
            start += int(size)
    return plans


def seam_speeds(joints: np.ndarray, fps: float) -> np.ndarray:
    """Mean joint speed (m/s) of every frame step: (..., T, J, 3) -> (..., T − 1)."""
    return np.linalg.norm(np.diff(joints, axis=-3), axis=-1).mean(-1) * fps


def boundary_report(
    joints: np.ndarray, seams: Sequence[int], fps: float, labels: Sequence = (), blends: Sequence[int] = ()
) -> list[dict]:
    """For one motion (T, J, 3): per seam frame s, the speed of the step s−1 → s (with ``blends[i]`` = b > 0 the
    fastest step from s−b−1 → s−b to s−1 → s), the motion's median step speed and their ratio (``labels``: what
    comes before and after each seam, optional)."""
    speed = seam_speeds(joints, fps)
    median = float(np.median(speed))
    rows = []
    for i, s in enumerate(seams):
        b = blends[i] if i < len(blends) else 0
        fastest = float(speed[s - 1 - b : s].max())
        row = {"frame": int(s), "seconds": round(s / fps, 4), "speed": fastest, "median_speed": median,
               "ratio": float(fastest / max(median, 1e-12))}  # fmt: skip
        if i < len(labels):
            row["before"], row["after"] = labels[i]
        rows.append(row)
    return rows


def generate_long(
    module,
    segments: Sequence[tuple[Any, float]],
    *,
    overlap_s: float = 1.0,
    blend_s: float = 0.25,
    num_samples: int = 1,
    generator: torch.Generator | None = None,
    labels: Sequence[str | None] | None = None,
    progress: bool = False,
    **sampling: Any,
) -> LongMotion:
    """``segments``: (condition, seconds) in order; a condition is what ``module.sample`` takes for a batch of
    ``num_samples`` (text features, action ids, or None). ``blend_s``: seconds at the end of each overlap that are
    cross-faded instead of held (0: hold all; 0.25 s took the largest seam step of the shipped cpu model from 3.0x
    to 2.3x its median step). ``sampling``: the options of ``SamplingOptions`` (mode, guidance, sampler, steps,
    eta, resample, hold_from, reconstruction). Returns ``num_samples`` long motions of Σ round(seconds · fps) frames
    each."""
    if not segments:
        raise ValueError("give at least one (condition, seconds) segment")
    conditioned = any(cond is not None for cond, _ in segments)
    options = SamplingOptions.from_kwargs(sampling).resolved(module, conditioned=conditioned)
    fps, max_frames = float(module.hparams.fps), int(module.hparams.max_frames)
    if not overlap_s > 0:
        raise ValueError(f"overlap must be positive seconds (the frames a segment continues from), got {overlap_s}")
    for k, (_, seconds) in enumerate(segments):
        if not seconds > 0 or round(seconds * fps) < 1:
            raise ValueError(f"segment {k + 1} lasts {seconds} s; it needs at least one frame (1/{fps:g} s)")
    labels = list(labels) if labels is not None else [None] * len(segments)
    frames = [round(seconds * fps) for _, seconds in segments]
    if not blend_s >= 0:
        raise ValueError(f"blend must be >= 0 seconds, got {blend_s}")
    overlap = max(1, round(overlap_s * fps))
    plans = plan_windows(frames, overlap, max_frames, min(round(blend_s * fps), overlap - 1))

    rep = module.representation
    mean, std = (t.detach().cpu().double().numpy() for t in (module.mean, module.std))
    held_kwargs = {**options.inpaint_kwargs(), "progress": progress}
    free_kwargs = {**options.sample_kwargs(), "progress": progress}
    motion = np.zeros((num_samples, 0, module.hparams.feature_dim))
    windows = []
    for plan in plans:
        cond = segments[plan.segment][0]
        if plan.overlap == 0:
            lengths = torch.full((num_samples,), plan.length)
            out = module.sample(cond, lengths, generator=generator, **free_kwargs)
            window = Window(plan, _denormalise(out, mean, std), np.zeros(num_samples), np.zeros((num_samples, 3)))
        else:
            window = _continue(module, motion, plan, cond, mean, std, generator=generator, **held_kwargs)
        check_finite_output(window.features, "the long motion")  # at once: the next window continues from it
        windows.append(window)
        placed = from_canonical(rep, window.features, window.yaw, window.offset)
        # the blended frames replace the motion's last ones (hml: rows before them decode unchanged)
        motion = np.concatenate([motion[:, : plan.start - plan.blend], placed[:, plan.held :]], axis=1)

    check_finite_output(motion, "the long motion")
    joints = rep.decode_numpy(motion)
    spans = [{"label": labels[k], "seconds": float(s), "start": int(sum(frames[:k])), "end": int(sum(frames[: k + 1]))}
             for k, (_, s) in enumerate(segments)]  # fmt: skip
    seams = [w.plan.start for w in windows[1:]]
    seam_labels = [(labels[a.plan.segment], labels[b.plan.segment]) for a, b in pairwise(windows)]
    blends = [w.plan.blend for w in windows[1:]]
    report = [boundary_report(j, seams, fps, seam_labels, blends) for j in joints]
    return LongMotion(motion, joints, fps, spans, windows, report)


def _continue(module, motion: np.ndarray, plan: WindowPlan, cond, mean, std, **sampling) -> Window:
    """The window that continues ``motion`` (B, plan.start, D): its overlap placed canonically, the held frames
    in-painted, the blended ones cross-faded, x_i ← (1 − w_i) x_i^before + w_i x_i^window, w_i = i / (b + 1)."""
    rep, b, held = module.representation, len(motion), plan.held
    first = plan.start - plan.overlap
    yaw, offset = placement(rep, motion, first)
    prefix = to_canonical(rep, motion[:, first:], yaw, offset)
    known = np.zeros((b, plan.length, len(mean)))
    known[:, :held] = (prefix[:, :held] - mean) / std
    keep = torch.zeros(b, plan.length, 1, dtype=torch.bool)
    keep[:, :held] = True
    out = inpaint(module, cond, torch.from_numpy(known).float(), keep, torch.full((b,), plan.length), **sampling)
    window = _denormalise(out, mean, std)
    window[:, :held] = prefix[:, :held]  # the held rows, without the float32 round trip of normalising
    w = (np.arange(1, plan.blend + 1) / (plan.blend + 1))[:, None]
    window[:, held : plan.overlap] = (1 - w) * prefix[:, held:] + w * window[:, held : plan.overlap]
    return Window(plan, window, yaw, offset)


def _denormalise(features: torch.Tensor, mean: np.ndarray, std: np.ndarray) -> np.ndarray:
    return features.detach().cpu().double().numpy() * std + mean


def check_long_settings(module, labels: Sequence, seconds: Sequence[float], overlap, blend, mode: str,
                        resample) -> tuple[float, float]:  # fmt: skip
    """(overlap, blend) in seconds for timed prompts, or one clear error for settings this model cannot do."""
    if mode not in EDIT_MODES:
        raise UsageError(f"edit_mode must be one of {', '.join(EDIT_MODES)}, got {mode!r}")
    if isinstance(resample, bool) or not isinstance(resample, int) or resample < 1:
        raise UsageError(f"resample is RePaint's repeats per step, a whole number >= 1 (1: none), got {resample!r}")
    fps, max_frames = module.hparams.fps, module.hparams.max_frames
    if isinstance(overlap, bool) or not isinstance(overlap, int | float) or not 0 < overlap * fps < max_frames - 0.5:
        raise UsageError(
            f"overlap is the seconds each prompt continues from the one before: more than 0 and less than this "
            f"model's {max_frames / fps:g} s, got {overlap!r}"
        )
    if isinstance(blend, bool) or not isinstance(blend, int | float) or not 0 <= blend < overlap:
        raise UsageError(f"blend is the seconds at the end of the overlap that are cross-faded: 0 to less than "
                         f"overlap={overlap:g}, got {blend!r}")  # fmt: skip
    short = [f"{p}:{s:g}" for p, s in zip(labels, seconds, strict=True) if round(s * fps) < 1]
    if short:
        raise UsageError(f"each timed prompt needs at least one frame (1/{fps:g} s): {', '.join(short)}")
    return float(overlap), float(blend)


def long_motion_info(long: LongMotion, mode: str, module) -> dict:
    """What results.json records of a long motion: its segments, windows, length, overlap and blend."""
    windows = [{"segment": w.plan.segment, "start": w.plan.start, "end": w.plan.end, "overlap": w.plan.overlap,
                "blend": w.plan.blend} for w in long.windows]  # fmt: skip
    return {"segments": long.segments, "windows": windows, "frames": long.num_frames,
            "seconds": long.num_frames / long.fps, "overlap_frames": max((w["overlap"] for w in windows), default=0),
            "blend_frames": max((w["blend"] for w in windows), default=0), "edit_mode": mode,
            "max_frames": int(module.hparams.max_frames)}  # fmt: skip


def seam_rows(long: LongMotion, smooth_sigma: float | None = None) -> list[dict]:
    """Per motion: its length and the speed jump at each seam against its median step (with ``smooth_sigma``, also
    after vvMDM's filter, which runs across the seams as it does on the saved joints)."""
    seams, blends = [w.plan.start for w in long.windows[1:]], [w.plan.blend for w in long.windows[1:]]
    rows = []
    for joints, boundaries in zip(long.joints, long.boundaries, strict=True):
        boundaries = [dict(b) for b in boundaries]
        if smooth_sigma:
            after = boundary_report(smooth_joints(joints, float(smooth_sigma)), seams, long.fps, blends=blends)
            for b, a in zip(boundaries, after, strict=True):
                b["ratio_smoothed"] = a["ratio"]
        rows.append({"frames": long.num_frames, "boundaries": boundaries,
                     "max_boundary_ratio": max((b["ratio"] for b in boundaries), default=None)})  # fmt: skip
    return rows
