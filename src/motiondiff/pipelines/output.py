"""What a pipeline returns: the generated motions as joints and as the model's features, with what is needed to save,
export or show them."""

from __future__ import annotations

import numbers
import tempfile
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np

from motiondiff.data.preparing.captions import measure
from motiondiff.data.representations import Representation
from motiondiff.data.representations.spec import HMLBridge
from motiondiff.edit.api import EditResult
from motiondiff.edit.cleanups import apply_cleanups, parse_cleanup
from motiondiff.edit.inputs import InputMotion
from motiondiff.edit.measures import mean_joint_speed
from motiondiff.edit.saving import save_edits
from motiondiff.edit.smoothing import smooth_joints, smoothness_of_joints
from motiondiff.export.html_viewer import export_html
from motiondiff.export.naming import motion_stems
from motiondiff.export.outputs import check_formats_for, export_features, parse_formats
from motiondiff.export.render import VIDEO_SIZE, render_motion
from motiondiff.export.smpl_mesh import render_body
from motiondiff.geometry.skeleton import Skeleton
from motiondiff.runtime.atomic import finite_or_null, save_npy, write_json
from motiondiff.runtime.errors import UsageError
from motiondiff.runtime.settings import check_settings


@dataclass
class MotionOutput:
    """Generated motions. ``joints[i]`` (frames, J, 3) in metres, y up, on ``skeleton``; ``features[i]`` the model's
    de-normalised features of the same motion; ``prompts[i]`` what it was generated from (None: unconditioned)."""

    joints: list[np.ndarray]
    features: list[np.ndarray]
    prompts: list[str | None]
    fps: float
    skeleton: Skeleton
    representation: Representation = field(repr=False)
    info: dict = field(default_factory=dict)  # how they were made (model, sampler, guidance, seed, edit settings)
    # the model's features -> the joints its measures read (SMPL-22/KIT-21; identity for hml263/kit251)
    bridge: HMLBridge | None = field(default=None, repr=False)
    # an edit's details (kept frames or joints, the input): `save` then writes the input and how well each edit kept it
    edit: EditResult | None = field(default=None, repr=False)
    source: InputMotion | None = field(default=None, repr=False)

    def __len__(self) -> int:
        return len(self.joints)

    def __repr__(self) -> str:
        """One line: how many motions, their lengths, the skeleton and the prompts (never the arrays)."""
        frames = sorted({len(j) for j in self.joints})
        lengths = ", ".join(f"{f / self.fps:g} s" for f in frames[:4]) + (", ..." if len(frames) > 4 else "")
        prompts = list(dict.fromkeys(self.prompts))
        shown = ", ".join(repr(p) for p in prompts[:3]) + (
            f", ... ({len(prompts)} prompts)" if len(prompts) > 3 else ""
        )
        return (f"MotionOutput({len(self)} motion(s) of {lengths} at {self.fps:g} fps on {self.skeleton.name} "
                f"({self.skeleton.num_joints} joints); prompts: {shown})")  # fmt: skip

    def seconds(self, i: int = 0) -> float:
        return len(self.joints[i]) / self.fps

    def save(
        self,
        folder: str | Path,
        formats=("bvh",),
        rig_names: str | None = None,
        *,
        render: str = "stick",
        smpl_model: str | Path | None = None,
        body=None,
        video_size: int = VIDEO_SIZE,
        summary: dict | None = None,
        overwrite: bool = False,
    ) -> list[dict]:
        """Write each motion's joints and features (.npy; the joints before smoothing or clean-up as *_joints_raw.npy)
        and the ``formats`` (bvh, mp4, gif, html, smpl) to ``folder``, with results.json: ``summary``, ``info`` and
        one row per motion with its files and what it measurably does (travel, speed, raised hands, smoothness
        before and after smoothing, what each clean-up did). The folder is created if needed; formats the skeleton
        cannot take (smpl off SMPL-22/24) are refused before anything is written. ``rig_names``: bone names of the
        bvh/fbx/glb files (smpl or mixamo; None: the skeleton's). ``render="mesh"`` with ``smpl_model=`` (the user's
        SMPL body model .npz; or an already loaded ``body``) makes the mp4/gif videos show that body's mesh;
        ``video_size``: their side in pixels (an even number from 64 to 2160; 720 by default). A folder
        that holds an earlier save (its results.json) or files of these motions' names is refused unless
        ``overwrite``: nothing already there is replaced without asking."""
        formats = parse_formats(list(formats) if not isinstance(formats, str) else formats)
        body = body if body is not None else render_body(render, smpl_model)
        check_formats_for(formats, self.representation.skeleton, rig_names, body, video_size)
        self._check_finite()
        folder = _output_folder(folder)
        long = self.info.get("long_motion")  # one motion through several prompts: long_<prompts joined by "then">_<k>
        names = [" then ".join(str(s["label"]) for s in long["segments"])] * len(self) if long else self.prompts
        stems = motion_stems(names, "long_" if long else "")  # <prompt>_<k>, as the commands
        if not overwrite:
            _refuse_earlier_files(folder, stems)
        title = [(s["start"], str(s["label"])) for s in long["segments"]] if long else None
        if self.edit is not None:
            rows = save_edits(folder, self, formats, rig_names, video_size=video_size)
        else:
            rows = [self._save_one(folder / stem, i, names[:i].count(names[i]), title, formats, rig_names, body,
                                   video_size) for i, stem in enumerate(stems)]  # fmt: skip
        doc = {**(summary or {}), "info": self.info, "samples": rows}
        write_json(folder / "results.json", finite_or_null(doc), default=str)
        return rows

    def _save_one(self, stem: Path, i: int, index: int, title, formats, rig_names, body, video_size) -> dict:
        """Motion ``i``'s files and results row; ``index``: its number among its prompt's motions (the stem's _k)."""
        joints, feats, prompt = self.joints[i], self.features[i], self.prompts[i]
        changed = self._changed(i)
        raw = self.representation.decode_numpy(feats).astype(np.float32) if changed is not None else None
        if raw is not None:
            save_npy(f"{stem}_joints_raw.npy", raw)
        save_npy(f"{stem}_joints.npy", joints.astype(np.float32))
        save_npy(f"{stem}_features.npy", np.asarray(feats, dtype=np.float32))
        exports = export_features(stem, self.representation, feats, self.fps, formats, title=title or prompt or
                                  "unconditioned", joints=changed, rig_names=rig_names, body=body,
                                  video_size=video_size)  # fmt: skip
        measured, smoothing = self._measured(i, raw)
        per_motion = self.info.get("per_motion") or [{}] * len(self)
        return {"prompt": prompt, "index": index, "frames": len(joints), "joints": f"{stem}_joints.npy",
                "features": f"{stem}_features.npy", "video": exports.get("mp4", exports.get("gif")),
                "exports": exports, "mean_joint_speed": mean_joint_speed(measured, self.fps),
                **asdict(measure(measured, self.fps)), **({"smoothing": smoothing} if smoothing else {}),
                **(self.info["cleanup"][i] if "cleanup" in self.info else {}), **per_motion[i]}  # fmt: skip

    def _measured(self, i: int, raw: np.ndarray | None = None) -> tuple[np.ndarray, dict | None]:
        """Motion ``i`` as its measures read it (on the features' skeleton, smoothed and cleaned as the saved
        joints were) and the smoothing report: vvMDM's smoothness before and after the filter. ``raw``: its
        features decoded, where the caller has them already."""
        bridge = self.bridge or HMLBridge(self.representation, self.representation.skeleton)
        measured = self.joints[i] if bridge.identity else bridge.joints(self.features[i])
        sigma, smoothing = self.info.get("smooth_sigma"), None
        if sigma:
            if not bridge.identity:
                raw = measured
            elif raw is None:
                raw = self.representation.decode_numpy(self.features[i]).astype(np.float32)
            smoothed = smooth_joints(raw, float(sigma))
            smoothing = {"sigma_frames": float(sigma), "measured_on": "HumanML3D features of the joints, as evaluate.py",
                         "smoothness_before": smoothness_of_joints(raw, bridge.feature_skeleton),
                         "smoothness_after": smoothness_of_joints(smoothed, bridge.feature_skeleton)}  # fmt: skip
            measured = measured if bridge.identity else smoothed
        cleanups = tuple(self.info.get("cleanups") or ())
        if cleanups and not bridge.identity:
            measured = apply_cleanups(measured, bridge.feature_skeleton, self.fps, cleanups)[0]
        return measured, smoothing

    def smoothed(self, sigma: float | None) -> MotionOutput:
        """These motions through vvMDM's Gaussian filter over time (``sigma`` in frames; None or 0: unchanged)."""
        sigma = check_settings(smooth_sigma=sigma)["smooth_sigma"]
        if not sigma:
            return self
        joints = [smooth_joints(j, sigma) for j in self.joints]
        return replace(self, joints=joints, info={**self.info, "smooth_sigma": float(sigma), "joints_changed": True})

    def cleaned(self, *cleanups: str) -> MotionOutput:
        """These motions after the named clean-ups (``"bones"``: one fixed skeleton, so every exported file agrees
        with the joints; ``"feet"``: feet pinned during ground contacts), in that order; what each did is in
        ``info["cleanup"]`` (one dict per motion)."""
        names = parse_cleanup(list(cleanups))
        kept = [
            None if self.edit is None else self.edit.kept_points(i) for i in range(len(self))
        ]  # an edit's kept part stays
        done = [
            apply_cleanups(j, self.skeleton, self.fps, names, keep=k) for j, k in zip(self.joints, kept, strict=True)
        ]
        info = {**self.info, "joints_changed": True, "cleanups": names, "cleanup": [report for _, report in done]}
        return replace(self, joints=[joints.astype(np.float32) for joints, _ in done], info=info)

    def to_bvh(self, i: int = 0) -> str:
        """The text of motion ``i`` as a BVH file (the model's rotations where it has them, else solved by IK)."""
        i = self._index(i)
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(export_features(Path(tmp) / "motion", self.representation, self.features[i], self.fps,
                                        ["bvh"], joints=self._changed(i))["bvh"])  # fmt: skip
            return path.read_text()

    def show(self, i: int = 0):
        """An interactive 3D view of motion ``i`` for a notebook (an IPython HTML object; its HTML in plain Python)."""
        i = self._index(i)

        with tempfile.TemporaryDirectory() as tmp:
            html = export_html(Path(tmp) / "motion.html", self.joints[i], self.skeleton, self.fps,
                               title=self.prompts[i] or "").read_text()  # fmt: skip
        try:
            from IPython.display import HTML
        except ImportError:
            return html
        return HTML(html)

    def gif(self, i: int = 0, size: int = 240):
        """Motion ``i`` as an animated GIF for a notebook (an IPython Image; the GIF bytes in plain Python), ``size``
        pixels square: small by default, as a saved notebook keeps it. Unlike ``show``'s interactive viewer, an image
        output stays in a saved notebook and shows on code hosts."""
        i = self._index(i)
        with tempfile.TemporaryDirectory() as tmp:
            data = render_motion(self.joints[i], self.skeleton, Path(tmp) / "motion.gif", title=self.prompts[i] or "",
                                 fps=self.fps, size=size).read_bytes()  # fmt: skip
        try:
            from IPython.display import Image
        except ImportError:
            return data
        return Image(data=data, format="gif")

    def _check_finite(self) -> None:
        """Refuse, before any file is written, motions holding NaN or Inf (a diverged sample)."""
        bad = [i for i, (j, f) in enumerate(zip(self.joints, self.features, strict=True))
               if not (np.isfinite(j).all() and np.isfinite(f).all())]  # fmt: skip
        if bad:
            raise UsageError(f"motion(s) {bad} hold NaN or Inf (a diverged sample); nothing was written: sample "
                             "them again, e.g. with another seed")  # fmt: skip

    def _index(self, i) -> int:
        """``i`` as the index of one of these motions, or one UsageError naming the valid range."""
        if isinstance(i, bool) or not isinstance(i, numbers.Integral) or not -len(self) <= i < len(self):
            raise UsageError(f"motion index {i!r} is out of range: this output holds {len(self)} motion(s), "
                             f"0 to {len(self) - 1}")  # fmt: skip
        return int(i) % len(self)

    def _changed(self, i: int) -> np.ndarray | None:
        """The joints when they are not the features decoded as they are (smoothed or edited after decoding)."""
        return self.joints[i] if self.info.get("joints_changed") else None


def _refuse_earlier_files(folder: Path, stems: list[str]) -> None:
    """Refuse a folder holding an earlier save (results.json) or a file named like one of ``stems``' files."""
    taken = sorted(p.name for p in folder.iterdir()
                   if p.name == "results.json" or any(p.name.startswith((f"{s}_", f"{s}.")) for s in stems))  # fmt: skip
    if taken:
        shown = ", ".join(taken[:3]) + (f" and {len(taken) - 3} more" if len(taken) > 3 else "")
        raise UsageError(f"{folder} already holds {shown}: save into a new folder, or pass overwrite=True to "
                         "replace them")  # fmt: skip


def _output_folder(folder) -> Path:
    """``folder`` created (parents too) as a writable folder, or one UsageError saying what it is and what to do."""
    if not isinstance(folder, str | Path) or not str(folder).strip():
        raise UsageError(f"save() takes a folder path (str or Path), got {type(folder).__name__}: e.g. save('out')")
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise UsageError(f"{folder} is a file, not a folder: save into a folder (a new or existing one)")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise UsageError(f"cannot create the folder {folder}: {err.strerror or err}; choose a folder you can write "
                         "to") from None  # fmt: skip
    return folder
