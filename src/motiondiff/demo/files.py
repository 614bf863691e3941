"""What one demo request writes, through `MotionOutput.save`: per motion the HTML viewer, an MP4, a BVH and an NPZ
(joints, features and fps in one file), FBX and GLB where Blender is available (`export.blender`, as export=fbx,glb),
and a zip of all of it. A Blender failure keeps the other files and is reported, not raised.
"""

from __future__ import annotations

import shutil
import subprocess
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from motiondiff.export.blender import BLENDER_FORMATS, blender_command
from motiondiff.pipelines import MotionOutput

PAGE_FORMATS = ["bvh", "mp4", "html"]
BLENDER_INCLUDED = "FBX and GLB: included (written by Blender from the BVH). BVH, FBX, GLB and NPZ are offered."
BLENDER_MISSING = ("FBX and GLB: not available in this install (they need Blender's bpy in a Python of its own, "
                   "named by MOTIONDIFF_BLENDER_PYTHON, or a blender executable: docs/usage.md, 'FBX and glTF "
                   "(GLB) files'). BVH and NPZ are offered.")  # fmt: skip
BLENDER_OFF = "FBX and GLB: turned off for this page (DemoModels(blender=False)). BVH and NPZ are offered."
BLENDER_ERRORS = (RuntimeError, OSError, subprocess.TimeoutExpired)  # what `convert_bvh` raises when Blender fails


def blender_available() -> bool:
    """Whether this install can write FBX/GLB files: Blender's bpy (or a Blender named by MOTIONDIFF_BLENDER_PYTHON)."""
    return blender_command() is not None


def blender_note(available: bool, failed: str | None = None) -> str:
    """The page's line on FBX/GLB downloads: included, turned off for this page, missing from this install (and how
    to get it), or, when Blender is there but could not write this request's files (``failed``: its error), that it
    failed."""
    if not available:
        return BLENDER_OFF if blender_available() else BLENDER_MISSING
    if failed:
        return f"FBX and GLB: Blender could not write them this time ({failed}). BVH and NPZ are offered."
    return BLENDER_INCLUDED


def download_kinds(blender: bool) -> str:
    """The per-motion download formats the page names."""
    return "BVH, FBX, GLB, NPZ" if blender else "BVH, NPZ"


@dataclass
class Sample:
    """One motion's files and its caption line for the page; ``fbx``/``glb`` None where they were not written."""

    index: int
    title: str
    html: Path
    mp4: Path
    bvh: Path
    npz: Path
    fbx: Path | None = None
    glb: Path | None = None

    def downloads(self) -> list[Path]:
        """The files the page offers for this motion: the BVH, the FBX and GLB when there are some, the NPZ."""
        return [p for p in (self.bvh, self.fbx, self.glb, self.npz) if p is not None]


def write_npz(path: Path, joints: np.ndarray, features: np.ndarray, fps: float) -> Path:
    """One motion in one file: joints (frames, J, 3) in metres, y up; the model's features; fps."""
    np.savez(path, joints=np.asarray(joints, np.float32), features=np.asarray(features, np.float32), fps=float(fps))
    return path


def write_samples(
    out: MotionOutput, folder: Path, *, blender: bool, video_size: int
) -> tuple[list[Sample], str | None]:
    """Each motion's files in ``folder`` (which must not exist yet) and the Blender error when ``blender`` was asked
    and failed (then the motions are saved again without FBX/GLB, into a clean folder)."""
    error = None
    rows = None
    if blender:
        try:
            rows = out.save(folder, formats=[*PAGE_FORMATS, *BLENDER_FORMATS], video_size=video_size)
        except BLENDER_ERRORS as err:
            error = str(err)
            shutil.rmtree(folder, ignore_errors=True)  # only this request's files: saved again below
    if rows is None:
        rows = out.save(folder, formats=PAGE_FORMATS, video_size=video_size)
    samples = []
    for i, row in enumerate(rows):
        files = {k: Path(v) for k, v in row["exports"].items() if k in (*PAGE_FORMATS, *BLENDER_FORMATS)}
        npz = write_npz(files["bvh"].with_suffix(".npz"), out.joints[i], out.features[i], out.fps)
        title = f"sample {i + 1}: {out.prompts[i] or 'unconditioned'}, {out.seconds(i):.1f} s at {out.fps:g} fps"
        samples.append(Sample(i, title, files["html"], files["mp4"], files["bvh"], npz, files.get("fbx"),
                              files.get("glb")))  # fmt: skip
    return samples, error


def zip_folder(folder: Path, target: Path) -> Path:
    """Every file under ``folder`` in one zip (paths inside it relative to the folder)."""
    with zipfile.ZipFile(target, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        for path in sorted(p for p in folder.rglob("*") if p.is_file()):
            archive.write(path, path.relative_to(folder).as_posix())
    return target
