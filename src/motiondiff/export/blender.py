"""FBX and glTF (GLB) files through Blender: the exported BVH is imported by Blender's own BVH importer and written
by its FBX / glTF exporters, so the files are what Blender itself makes of the motion.

Blender runs in a child process, never inside this one (its bundled libraries and ours stay apart). The child is
the Python named by ``MOTIONDIFF_BLENDER_PYTHON`` (a Python with the ``bpy`` module, or a ``blender`` executable,
which runs the script with ``--background --python``), else this Python when it has ``bpy``. bpy lives best in a
venv of its own: its wheels pin numpy<2, this package needs numpy>=2.4, so the two cannot share one environment's
resolver (INSTALL_HINT). Without Blender, asking for fbx/glb is one clear error before any work.

The files carry a body: the mannequin of `geometry.mannequin`, built on the BVH's own rest skeleton, handed to the
child as a JSON file in a scratch folder (rest vertices, triangles, each vertex's bone) and bound to the armature
with one vertex group per bone, so Blender or a glTF viewer shows a body with no SMPL file.

Frames: the BVH's frame k (1..N) is scene frame k at the motion's fps, and the child sets the scene to 1..N (the BVH
importer would only extend the default 1..250, to N + 1). An FBX stores its frame rate, which Blender's importer applies;
a glTF stores seconds, frame k at k / fps, and Blender's glTF importer turns them into frames by the scene's own
rate, so a 20 fps GLB opened in a default 24 fps scene starts at frame 1.2 (set the scene's rate to the motion's
first). The glTF add-on converts frames and seconds by fps * fps_base where Blender's rate is fps / fps_base: the
child sets fps_base so that both agree on the motion's rate for the glTF (they differ only at a fractional rate
such as KIT-ML's 12.5 fps).
"""

from __future__ import annotations

import importlib.util
import json
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

from motiondiff.data.formats.bvh import BVHMotion, read_bvh
from motiondiff.geometry.mannequin import build_mannequin
from motiondiff.geometry.skeleton import Skeleton
from motiondiff.runtime.errors import UsageError

BLENDER_FORMATS = ("fbx", "glb")
INSTALL_HINT = (
    "fbx/glb export needs Blender in a Python of its own (bpy pins numpy<2): python3.11 -m venv blender-env && "
    'blender-env/bin/pip install "bpy>=5.0,<6", then set MOTIONDIFF_BLENDER_PYTHON=blender-env/bin/python '
    "(or to a blender executable)"
)

# Run by the child: import the BVH at its own frame rate (one BVH frame = one scene frame, 1..N), bind the mannequin
# (if given) to the armature, write the armature's animation and the mesh. Only bpy and the standard library: the
# child has no motiondiff.
_SCRIPT = r"""
import json, sys, bpy, addon_utils
from bpy_extras.io_utils import axis_conversion
bvh, out, fps, frames, body = sys.argv[-5], sys.argv[-4], float(sys.argv[-3]), int(sys.argv[-2]), sys.argv[-1]
for module in ("io_anim_bvh", "io_scene_fbx", "io_scene_gltf2"):
    addon_utils.enable(module, default_set=True)
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
scene.render.fps, scene.render.fps_base = round(fps), round(fps) / fps
bpy.ops.import_anim.bvh(filepath=bvh, global_scale=1.0, use_fps_scale=False, update_scene_fps=False,
                        update_scene_duration=False, axis_forward="-Z", axis_up="Y")
arm = next(o for o in scene.objects if o.type == "ARMATURE")
scene.frame_start, scene.frame_end = 1, frames
types = {"ARMATURE"}
if body:
    with open(body) as f:
        data = json.load(f)
    mesh = bpy.data.meshes.new("mannequin")
    mesh.from_pydata(data["vertices"], [], data["faces"])
    mesh.transform(axis_conversion(from_forward="-Z", from_up="Y").to_4x4())  # the BVH importer's axes
    mesh.shade_smooth()
    obj = bpy.data.objects.new("mannequin", mesh)
    scene.collection.objects.link(obj)
    for name, members in zip(data["bones"], data["members"]):
        obj.vertex_groups.new(name=name).add(members, 1.0, "REPLACE")
    obj.parent = arm
    obj.modifiers.new("armature", "ARMATURE").object = arm
    types.add("MESH")
if out.endswith(".fbx"):
    bpy.ops.export_scene.fbx(filepath=out, object_types=types, add_leaf_bones=False, bake_anim=True,
                             bake_anim_simplify_factor=0.0)
else:
    scene.render.fps_base = fps / round(fps)  # the glTF add-on's rate is fps * fps_base (module doc)
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


def convert_bvh(
    bvh: str | Path,
    out: str | Path,
    fps: float,
    timeout: float = 300,
    *,
    skeleton: Skeleton | None = None,
    body: bool = True,
) -> Path:
    """Write ``out`` (.fbx or .glb) from the BVH file ``bvh`` with Blender; a partial file is never left. ``body``: with
    the mannequin bound to the armature; ``skeleton``: the skeleton the BVH was written from (its joint names as the
    file's bones), whose body parts shape the mannequin (default: read from the file's joint names)."""
    bvh, out = Path(bvh), Path(out)
    if out.suffix.lower() not in (".fbx", ".glb"):
        raise ValueError(f"cannot convert to {out.name}: use a .fbx or .glb file name")
    command = blender_command()
    if command is None:
        raise UsageError(INSTALL_HINT)
    tmp = out.with_name(f".{out.stem}.partial{out.suffix}")
    args = ["--"] if "--python-expr" in command else []
    motion = read_bvh(bvh)
    with tempfile.TemporaryDirectory(prefix="motiondiff_blender_") as scratch:
        mesh = ""
        if body:
            mesh = str(Path(scratch) / "mannequin.json")
            Path(mesh).write_text(json.dumps(mannequin_for_bvh(motion, skeleton)))
        proc = subprocess.run([*command, _SCRIPT, *args, str(bvh), str(tmp), repr(float(fps)), str(motion.num_frames),
                               mesh], capture_output=True, text=True, timeout=timeout)  # fmt: skip
    if proc.returncode != 0 or not tmp.is_file():
        tmp.unlink(missing_ok=True)
        tail = (proc.stderr or proc.stdout).strip().splitlines()[-3:]
        raise RuntimeError(f"Blender could not write {out.name} from {bvh.name}: {' | '.join(tail)}")
    return tmp.replace(out)


def mannequin_for_bvh(motion: BVHMotion, skeleton: Skeleton | None = None) -> dict:
    """The mannequin of a BVH's rest skeleton as the child reads it: rest ``vertices`` (V, 3) in the file's units
    and axes, ``faces`` (F, 3), ``bones`` (the file's joint names) and ``members`` (each bone's vertex indices).
    ``skeleton``: the skeleton the file was written from (names with whitespace as "_", as `export_bvh` writes them),
    whose body parts shape the mannequin; default, or when its names are not the file's: `Skeleton.infer`."""
    names = [re.sub(r"\s+", "_", n) for n in skeleton.joint_names] if skeleton is not None else []
    if names and sorted(names) == sorted(motion.joint_names):
        shaped = skeleton.with_offsets(motion.offsets[[motion.joint_names.index(n) for n in names]])
    else:
        shaped, names = motion.skeleton(), list(motion.joint_names)
    mannequin = build_mannequin(shaped)
    return {
        "vertices": mannequin.rest_vertices().round(6).tolist(),
        "faces": mannequin.faces.tolist(),
        "bones": names,
        "members": [[int(v) for v in (mannequin.owners == j).nonzero()[0]] for j in range(len(names))],
    }
