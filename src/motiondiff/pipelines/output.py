"""What a pipeline returns: the generated motions as joints and as the model's features, with what is needed to save,
export or show them."""

from __future__ import annotations

import tempfile
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from motiondiff.data.representations import Representation
from motiondiff.edit.cleanups import apply_cleanups, parse_cleanup
from motiondiff.export.naming import motion_stems
from motiondiff.export.outputs import check_formats_for, export_features, parse_formats
from motiondiff.export.smpl_mesh import render_body
from motiondiff.geometry.skeleton import Skeleton
from motiondiff.runtime.atomic import finite_or_null, save_npy, write_json


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
    ) -> list[dict]:
        """Write each motion's joints and features (.npy) and the ``formats`` (bvh, mp4, gif, html, smpl) to
        ``folder``, with results.json listing the files; returns its rows. The folder is created if needed; formats
        the skeleton cannot take (smpl off SMPL-22/24) are refused before anything is written. ``rig_names``: bone
        names of the bvh/fbx/glb files (smpl or mixamo; None: the skeleton's). ``render="mesh"`` with
        ``smpl_model=`` (the user's SMPL body model .npz) makes the mp4/gif videos show that body's mesh."""
        formats = parse_formats(list(formats) if not isinstance(formats, str) else formats)
        body = render_body(render, smpl_model)
        check_formats_for(formats, self.representation.skeleton, rig_names, body)
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        rows = []
        stems = motion_stems(self.prompts)  # the commands' scheme: <prompt>_<k>
        for i, (joints, feats, prompt) in enumerate(zip(self.joints, self.features, self.prompts, strict=True)):
            stem = folder / stems[i]
            save_npy(f"{stem}_joints.npy", joints.astype(np.float32))
            save_npy(f"{stem}_features.npy", feats.astype(np.float32))
            exports = export_features(stem, self.representation, feats, self.fps, formats, title=prompt or "",
                                      joints=self._changed(i), rig_names=rig_names, body=body)  # fmt: skip
            rows.append({"prompt": prompt, "index": i, "frames": len(joints), "joints": f"{stem}_joints.npy",
                         "features": f"{stem}_features.npy", "exports": exports})  # fmt: skip
        write_json(folder / "results.json", finite_or_null({"info": self.info, "samples": rows}), default=str)
        return rows

    def cleaned(self, *cleanups: str) -> MotionOutput:
        """These motions after the named clean-ups (``"bones"``: one fixed skeleton, so every exported file agrees
        with the joints; ``"feet"``: feet pinned during ground contacts), in that order; what each did is in
        ``info["cleanup"]`` (one dict per motion)."""
        names = parse_cleanup(list(cleanups))
        done = [apply_cleanups(j, self.skeleton, self.fps, names) for j in self.joints]
        info = {**self.info, "joints_changed": True, "cleanup": [report for _, report in done]}
        return replace(self, joints=[joints.astype(np.float32) for joints, _ in done], info=info)

    def to_bvh(self, i: int = 0) -> str:
        """The text of motion ``i`` as a BVH file (the model's rotations where it has them, else solved by IK)."""
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(export_features(Path(tmp) / "motion", self.representation, self.features[i], self.fps,
                                        ["bvh"], joints=self._changed(i))["bvh"])  # fmt: skip
            return path.read_text()

    def show(self, i: int = 0):
        """An interactive 3D view of motion ``i`` for a notebook (an IPython HTML object; its HTML in plain Python)."""
        from motiondiff.export.html_viewer import export_html

        with tempfile.TemporaryDirectory() as tmp:
            html = export_html(Path(tmp) / "motion.html", self.joints[i], self.skeleton, self.fps,
                               title=self.prompts[i] or "").read_text()  # fmt: skip
        try:
            from IPython.display import HTML
        except ImportError:
            return html
        return HTML(html)

    def gif(self, i: int = 0, dpi: int = 60):
        """Motion ``i`` as an animated GIF for a notebook (an IPython Image; the GIF bytes in plain Python). Unlike
        ``show``'s interactive viewer, an image output stays in a saved notebook and shows on code hosts."""
        from motiondiff.export.render import render_motion

        with tempfile.TemporaryDirectory() as tmp:
            data = render_motion(self.joints[i], self.skeleton, Path(tmp) / "motion.gif", title=self.prompts[i] or "",
                                 fps=self.fps, dpi=dpi).read_bytes()  # fmt: skip
        try:
            from IPython.display import Image
        except ImportError:
            return data
        return Image(data=data, format="gif")

    def _changed(self, i: int) -> np.ndarray | None:
        """The joints when they are not the features decoded as they are (smoothed or edited after decoding)."""
        return self.joints[i] if self.info.get("joints_changed") else None
