"""Measures of an edited or generated motion that results.json reports: how exactly an edit kept its input
(largest error on the kept frames or joints), how its kept/generated boundaries move against the generated middle
(step speed and velocity change, over the middle's median speed), and a motion's mean joint speed and acceleration.
Commands, the editing study and the behaviour study share them."""

from __future__ import annotations

import numpy as np

SPEED_FLOOR = 0.1  # m/s: the least "median generated speed" a boundary jump is divided by


def mean_joint_speed(joints: np.ndarray, fps: float) -> float:
    """Mean norm of the joints' frame-to-frame steps in m/s."""
    return float(np.linalg.norm(np.diff(joints, axis=0), axis=-1).mean() * fps)


def mean_joint_acceleration(joints: np.ndarray, fps: float) -> float:
    """Mean norm of the joints' second differences in m/s^2 (0 for clips under 3 frames)."""
    if len(joints) < 3:
        return 0.0
    return float(np.linalg.norm(np.diff(joints, n=2, axis=0), axis=-1).mean() * fps**2)


def step_speeds(joints: np.ndarray, fps: float) -> np.ndarray:
    """(N-1,) speed of each frame-to-frame step, mean over joints of |x_{k+1} - x_k| · fps (m/s)."""
    return np.linalg.norm(np.diff(np.asarray(joints, dtype=np.float64), axis=0), axis=-1).mean(-1) * fps


def kept_max_error(joints: np.ndarray, input_joints: np.ndarray, kept: np.ndarray) -> float:
    """Largest distance (m) between edited and input joints where ``kept`` ((N, J) bool) fixes them."""
    dist = np.linalg.norm(np.asarray(joints, np.float64) - np.asarray(input_joints, np.float64), axis=-1)
    return float(dist[kept].max()) if kept.any() else 0.0


def root_relative_max_error(joints: np.ndarray, input_joints: np.ndarray, kept_joints) -> float:
    """Largest distance (m) of the kept joints relative to the root (joint 0), over every frame."""
    rel = np.asarray(joints, np.float64) - np.asarray(joints, np.float64)[:, :1]
    rel_in = np.asarray(input_joints, np.float64) - np.asarray(input_joints, np.float64)[:, :1]
    idx = list(kept_joints)
    return float(np.linalg.norm(rel[:, idx] - rel_in[:, idx], axis=-1).max()) if idx else 0.0


def velocity_changes(joints: np.ndarray, fps: float) -> np.ndarray:
    """(N-2,) change of velocity between consecutive steps, mean over joints of |Δx_{k+1} − Δx_k| · fps (m/s)."""
    steps = np.diff(np.asarray(joints, dtype=np.float64), axis=0)
    return np.linalg.norm(np.diff(steps, axis=0), axis=-1).mean(-1) * fps


def boundary_jumps(joints: np.ndarray, kept_frames: np.ndarray, fps: float, floor: float = SPEED_FLOOR) -> dict:
    """Each kept/generated boundary's step speed over the generated middle's median step speed (module docstring),
    and the change of velocity there: the larger of the changes into and out of the boundary step, over the same
    scale ("change_ratio"; a kept part that ends in a fast kick has a fast boundary step however seamless the edit,
    its velocity change is what a seam adds). Returns {"median_generated_speed", "boundaries": [{"frame", "side",
    "speed", "ratio", "speed_change", "change_ratio"}]}; "frame" is the first frame after the boundary, "side"
    "start" (kept -> generated) or "end" (generated -> kept)."""
    speeds, changes = step_speeds(joints, fps), velocity_changes(joints, fps)
    kept = np.asarray(kept_frames, dtype=bool)
    middle = ~kept[:-1] & ~kept[1:]
    median = float(np.median(speeds[middle])) if middle.any() else 0.0
    scale = max(median, floor)
    rows = []
    for k in np.flatnonzero(kept[:-1] != kept[1:]):  # step k crosses the boundary; changes[k-1], changes[k] touch it
        change = float(max(changes[max(k - 1, 0) : k + 1], default=0.0))
        rows.append({"frame": int(k + 1), "side": "start" if kept[k] else "end", "speed": float(speeds[k]),
                     "ratio": float(speeds[k] / scale), "speed_change": change,
                     "change_ratio": change / scale})  # fmt: skip
    return {"median_generated_speed": median, "boundaries": rows}


def edit_numbers(result, i: int, fps: float) -> dict:
    """What results.json reports per edit: kept-part error, and boundary jumps (in-betweening) or the kept joints'
    root-relative error (body parts)."""
    joints, inputs = result.joints[i], result.input_joints[i]
    row = {"kept_max_error_m": kept_max_error(joints, inputs, result.kept_points(i))}
    if result.kind == "inbetween":
        kept = result.kept_frames[i]
        jumps = boundary_jumps(joints, kept, fps)
        row.update(
            jumps,
            max_boundary_ratio=max((b["ratio"] for b in jumps["boundaries"]), default=0.0),
            max_change_ratio=max((b["change_ratio"] for b in jumps["boundaries"]), default=0.0),
        )
        # a jittery middle makes every boundary look small next to it: its speed next to the input's tells
        middle = ~kept[:-1] & ~kept[1:]
        row["median_input_speed"] = float(np.median(step_speeds(inputs, fps)[middle])) if middle.any() else 0.0
    else:
        row["root_relative_kept_max_error_m"] = root_relative_max_error(joints, inputs, result.kept_joints)
    return row
