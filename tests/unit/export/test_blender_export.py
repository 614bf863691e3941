"""FBX/GLB through Blender: the files re-import into Blender with the skeleton's 22 bones and the motion's frame
count; without Blender, asking for them is one clear error. Skipped where no Blender is available (set
MOTIONDIFF_BLENDER_PYTHON to a Python with bpy, or pip install "motiondiff[blender]")."""

from __future__ import annotations

import subprocess

import pytest
from fixtures.synthetic_motion import glide

from motiondiff.export.blender import BLENDER_FORMATS, blender_command, check_blender, convert_bvh
from motiondiff.export.bvh_export import export_bvh
from motiondiff.geometry.skeleton import SMPL22
from motiondiff.runtime.errors import UsageError

REIMPORT = r"""
import sys, bpy, addon_utils
path, fps = sys.argv[-2], float(sys.argv[-1])
for module in ("io_scene_fbx", "io_scene_gltf2"):
    addon_utils.enable(module, default_set=True)
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.context.scene.render.fps, bpy.context.scene.render.fps_base = round(fps), round(fps) / fps
(bpy.ops.import_scene.fbx if path.endswith(".fbx") else bpy.ops.import_scene.gltf)(filepath=path)
arm = next(o for o in bpy.data.objects if o.type == "ARMATURE")
start, end = arm.animation_data.action.frame_range
print("RESULT", len(arm.data.bones), round(end - start) + 1)
"""


def test_without_blender_fbx_is_one_clear_error(monkeypatch):
    monkeypatch.setattr("motiondiff.export.blender.blender_command", lambda: None)
    check_blender(["bvh", "mp4"])  # nothing asked of Blender: fine
    with pytest.raises(UsageError, match=r'pip install "motiondiff\[blender\]"'):
        check_blender(["bvh", "glb"])


@pytest.mark.skipif(blender_command() is None, reason="no Blender: pip install 'motiondiff[blender]' or set "
                    "MOTIONDIFF_BLENDER_PYTHON")  # fmt: skip
@pytest.mark.parametrize("fmt", BLENDER_FORMATS)
def test_blender_files_reimport_with_every_bone_and_frame(tmp_path, fmt):
    frames, fps = 40, 20.0
    bvh = export_bvh(tmp_path / "walk.bvh", glide(30, 1.5, frames=frames), SMPL22, fps).path
    out = convert_bvh(bvh, tmp_path / f"walk.{fmt}", fps)
    command = blender_command()
    args = ["--"] if "--python-expr" in command else []
    proc = subprocess.run([*command, REIMPORT, *args, str(out), str(fps)], capture_output=True, text=True, timeout=300)
    result = next(line for line in proc.stdout.splitlines() if line.startswith("RESULT"))
    assert result.split()[1:] == ["22", str(frames)], proc.stdout[-2000:]
    assert not list(tmp_path.glob(".*partial*"))
