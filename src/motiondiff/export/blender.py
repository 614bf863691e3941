"""FBX and glTF (GLB) files through Blender: the exported BVH is imported by Blender's own BVH importer and written
by its FBX / glTF exporters, so the files are what Blender itself makes of the motion.

Blender runs in a child process, never inside this one (its bundled libraries and ours stay apart). The child is
the Python named by ``MOTIONDIFF_BLENDER_PYTHON`` (a Python with the ``bpy`` module, or a ``blender`` executable,
which runs the script with ``--background --python``), else this Python when it has ``bpy``
(``pip install "motiondiff[blender]"``). Without either, asking for fbx/glb is one clear error before any work.
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from pathlib import Path

from motiondiff.runtime.errors import UsageError

BLENDER_FORMATS = ("fbx", "glb")
INSTALL_HINT = (
    'fbx/glb export needs Blender: pip install "motiondiff[blender]" (the bpy module, Python 3.11, about 400 MB), '
    "or set MOTIONDIFF_BLENDER_PYTHON to a Python with bpy or to a blender executable"
)

# Run by the child: import the BVH at its own frame rate (one BVH frame = one scene frame), write the armature's
# animation, nothing else. Only bpy and the standard library: the child has no motiondiff.
_SCRIPT = r"""
import sys, bpy, addon_utils
bvh, out, fps = sys.argv[-3], sys.argv[-2], float(sys.argv[-1])
for module in ("io_anim_bvh", "io_scene_fbx", "io_scene_gltf2"):
    addon_utils.enable(module, default_set=True)
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
scene.render.fps, scene.render.fps_base = round(fps), round(fps) / fps
bpy.ops.import_anim.bvh(filepath=bvh, global_scale=1.0, use_fps_scale=False, update_scene_fps=False,
                        update_scene_duration=True)
if out.endswith(".fbx"):
    bpy.ops.export_scene.fbx(filepath=out, object_types={"ARMATURE"}, add_leaf_bones=False, bake_anim=True,
                             bake_anim_simplify_factor=0.0)
else:
    bpy.ops.export_scene.gltf(filepath=out, export_format="GLB", export_animations=True,
                              export_frame_range=True, export_force_sampling=True)
"""


def blender_command() -> list[str] | None:
    """The command that runs a Python script with Blender, or None when there is no Blender to run."""
    named = os.environ.get("MOTIONDIFF_BLENDER_PYTHON")
    if named:
        if Path(named).name.lower().startswith("blender"):
            return [named, "--background", "--factory-startup", "--python-expr"]
        return [named, "-c"]
    if importlib.util.find_spec("bpy") is not None:
        return [sys.executable, "-c"]
    return None


def check_blender(formats) -> None:
    """One clear error, before any work, when fbx/glb are asked for and there is no Blender."""
    if any(f in BLENDER_FORMATS for f in formats) and blender_command() is None:
        raise UsageError(INSTALL_HINT)


def convert_bvh(bvh: str | Path, out: str | Path, fps: float, timeout: float = 300) -> Path:
    """Write ``out`` (.fbx or .glb) from the BVH file ``bvh`` with Blender; a partial file is never left."""
    bvh, out = Path(bvh), Path(out)
    if out.suffix.lower() not in (".fbx", ".glb"):
        raise ValueError(f"cannot convert to {out.name}: use a .fbx or .glb file name")
    command = blender_command()
    if command is None:
        raise UsageError(INSTALL_HINT)
    tmp = out.with_name(f".{out.stem}.partial{out.suffix}")
    args = ["--"] if "--python-expr" in command else []
    proc = subprocess.run([*command, _SCRIPT, *args, str(bvh), str(tmp), repr(float(fps))], capture_output=True,
                          text=True, timeout=timeout)  # fmt: skip
    if proc.returncode != 0 or not tmp.is_file():
        tmp.unlink(missing_ok=True)
        tail = (proc.stderr or proc.stdout).strip().splitlines()[-3:]
        raise RuntimeError(f"Blender could not write {out.name} from {bvh.name}: {' | '.join(tail)}")
    return tmp.replace(out)
