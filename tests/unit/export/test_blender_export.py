"""FBX/GLB through Blender, with the mannequin: re-imported into Blender, each file has the skeleton's 22 bones, one
mesh bound to them (armature parent and modifier, a vertex group per bone), keys on exactly frames 1..N at the
motion's fps, and at frames 1 and N the bones and the skinned mesh where the BVH's frames 1 and N put them (so no
frame is shifted). The GLB's own clock (seconds) is checked from its JSON: frame k at k / fps, also at a fractional
rate. Without Blender, asking for fbx/glb is one clear error. The Blender tests are skipped where no Blender is
available (MOTIONDIFF_BLENDER_PYTHON naming a Python with bpy: docs/usage.md, "FBX and glTF (GLB) files")."""

from __future__ import annotations

import json
import struct
import subprocess

import numpy as np
import pytest
from fixtures.synthetic_motion import glide
from scipy.spatial import cKDTree

from motiondiff.data.formats.bvh import read_bvh
from motiondiff.export.blender import blender_command, check_blender, convert_bvh, mannequin_for_bvh
from motiondiff.export.bvh_export import export_bvh
from motiondiff.geometry.mannequin import build_mannequin
from motiondiff.geometry.skeleton import SMPL22
from motiondiff.runtime.errors import UsageError

needs_blender = pytest.mark.skipif(blender_command() is None, reason="no Blender: set MOTIONDIFF_BLENDER_PYTHON to a "
                                   "Python with bpy (docs/usage.md)")  # fmt: skip

# Re-imports each file into a fresh scene and prints one JSON line per file. The FBX goes into Blender's default
# 24 fps scene (the file carries its rate); a glTF has no rate, so its scene is set to the motion's first.
REIMPORT = r"""
import json, sys, bpy, addon_utils
glb, fbx, fps, last = sys.argv[-4], sys.argv[-3], float(sys.argv[-2]), int(sys.argv[-1])
for module in ("io_scene_fbx", "io_scene_gltf2"):
    addon_utils.enable(module, default_set=True)
for path in (glb, fbx):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    if path == glb:
        scene.render.fps, scene.render.fps_base = round(fps), 1.0
        bpy.ops.import_scene.gltf(filepath=path, disable_bone_shape=True)
    else:
        bpy.ops.import_scene.fbx(filepath=path)
    arm = next(o for o in scene.objects if o.type == "ARMATURE")
    action = arm.animation_data.action
    curves = list(getattr(action, "fcurves", None) or [c for layer in action.layers for strip in layer.strips
                                                        for bag in strip.channelbags for c in bag.fcurves])
    meshes = [o for o in scene.objects if o.type == "MESH"]
    posed = {}
    for frame in (1, last):
        scene.frame_set(frame)
        graph = bpy.context.evaluated_depsgraph_get()
        heads = {b.name: list(arm.matrix_world @ b.head) for b in arm.pose.bones}
        shown = [o.evaluated_get(graph) for o in meshes]
        posed[frame] = {"heads": heads, "vertices": [list(o.matrix_world @ v.co) for o in shown for v in o.data.vertices]}
    print("RESULT " + json.dumps({
        "fps": scene.render.fps / scene.render.fps_base, "bones": [b.name for b in arm.data.bones],
        "keys": sorted({k.co[0] for c in curves for k in c.keyframe_points}),
        "meshes": [{"vertices": len(o.data.vertices), "parent": o.parent.name if o.parent else None,
                    "modifiers": [m.object.name for m in o.modifiers if m.type == "ARMATURE" and m.object],
                    "groups": [g.name for g in o.vertex_groups]} for o in meshes],
        "armature": arm.name, "posed": posed}))
"""


def glb_key_times(path) -> list[tuple[float, float]]:
    """(first, last) key time in seconds of every animation sampler of a GLB, from its JSON chunk (glTF requires an
    animation input accessor to hold its min and max)."""
    data = path.read_bytes()
    length, kind = struct.unpack_from("<I4s", data, 12)
    assert data[:4] == b"glTF" and kind == b"JSON"
    doc = json.loads(data[20 : 20 + length])
    inputs = [doc["accessors"][s["input"]] for a in doc["animations"] for s in a["samplers"]]
    return [(a["min"][0], a["max"][0]) for a in inputs]


def z_up(points) -> np.ndarray:
    """Our y-up metres as Blender's BVH importer places them (z up, our z towards -y)."""
    points = np.asarray(points, dtype=np.float64)
    return np.stack([points[..., 0], -points[..., 2], points[..., 1]], axis=-1)


def bvh_frame(bvh, frame: int) -> tuple[dict, np.ndarray]:
    """Joint positions by name and the mannequin's skinned vertices at BVH frame `frame` (0-based), in Blender axes."""
    motion = read_bvh(bvh)
    order = [motion.joint_names.index(n) for n in SMPL22.joint_names]
    mannequin = build_mannequin(SMPL22.with_offsets(motion.offsets[order]))
    rotations, root = motion.rotations[:, order], motion.translations[:, order[0]]
    joints = z_up(motion.positions()[frame])
    vertices = z_up(mannequin.posed(rotations[frame : frame + 1], root[frame : frame + 1])[0])
    return dict(zip(motion.joint_names, joints, strict=True)), vertices


def test_without_blender_fbx_is_one_clear_error(monkeypatch):
    monkeypatch.setattr("motiondiff.export.blender.blender_command", lambda: None)
    check_blender(["bvh", "mp4"])  # nothing asked of Blender: fine
    with pytest.raises(UsageError, match=r'pip install "bpy>=5.0,<6", then set MOTIONDIFF_BLENDER_PYTHON'):
        check_blender(["bvh", "glb"])


def test_the_mannequin_handed_to_blender_binds_every_vertex_to_a_bone_of_the_file(tmp_path):
    bvh = export_bvh(tmp_path / "walk.bvh", glide(30, 1.5, frames=4), SMPL22, 20.0).path
    motion = read_bvh(bvh)
    for skeleton in (SMPL22, None):  # the file's skeleton given, or read from its joint names
        data = mannequin_for_bvh(motion, skeleton)
        assert sorted(data["bones"]) == sorted(motion.joint_names)
        members = np.concatenate([m for m in data["members"] if m])
        assert sorted(members.tolist()) == list(range(len(data["vertices"])))  # each vertex in exactly one group
        assert np.asarray(data["faces"]).max() == len(data["vertices"]) - 1
        assert sum(1 for m in data["members"] if m) == 22  # every bone carries a piece


@needs_blender
@pytest.mark.parametrize("fps, frames", [(20.0, 23), (30.0, 17)])
def test_blender_files_reimport_with_the_mannequin_on_frames_1_to_n(tmp_path, fps, frames):
    motion = glide(30, 1.5, frames=frames) + np.linspace(0, 0.3, frames)[:, None, None] * [0.0, 1.0, 0.0]
    bvh = export_bvh(tmp_path / "walk.bvh", motion, SMPL22, fps).path
    glb, fbx = (convert_bvh(bvh, tmp_path / f"walk.{fmt}", fps, skeleton=SMPL22) for fmt in ("glb", "fbx"))
    assert not list(tmp_path.glob(".*partial*"))
    for first, last in glb_key_times(glb):  # the GLB's clock: frame k at k / fps seconds
        assert first == pytest.approx(1 / fps, abs=1e-6) and last == pytest.approx(frames / fps, abs=1e-6)
    command = blender_command()
    args = ["--"] if "--python-expr" in command else []
    proc = subprocess.run([*command, REIMPORT, *args, str(glb), str(fbx), str(fps), str(frames)],
                          capture_output=True, text=True, timeout=300)  # fmt: skip
    results = [json.loads(line[7:]) for line in proc.stdout.splitlines() if line.startswith("RESULT ")]
    assert len(results) == 2, proc.stderr[-2000:]
    vertices = len(build_mannequin(SMPL22).owners)
    for result in results:
        assert result["fps"] == pytest.approx(fps)
        assert sorted(result["bones"]) == sorted(SMPL22.joint_names)
        assert result["keys"] == list(range(1, frames + 1))  # every frame, from 1, none shifted
        (mesh,) = result["meshes"]
        assert mesh["vertices"] == vertices and sorted(mesh["groups"]) == sorted(SMPL22.joint_names)
        assert mesh["parent"] == result["armature"] and mesh["modifiers"] == [result["armature"]]
        for key, frame in (("1", 0), (str(frames), frames - 1)):  # Blender frame k is the BVH's k-th frame
            joints, skinned = bvh_frame(bvh, frame)
            heads = result["posed"][key]["heads"]
            assert max(np.linalg.norm(np.subtract(heads[n], joints[n])) for n in SMPL22.joint_names) < 1e-3
            shown = np.asarray(result["posed"][key]["vertices"])
            assert cKDTree(skinned).query(shown)[0].max() < 1e-3 and cKDTree(shown).query(skinned)[0].max() < 1e-3


@needs_blender
def test_a_fractional_frame_rate_keeps_the_glb_clock(tmp_path):
    fps, frames = 12.5, 6  # KIT-ML's rate: Blender's glTF add-on would time it at 12 * 0.96 = 11.52 fps
    bvh = export_bvh(tmp_path / "walk.bvh", glide(0, 0.5, frames=frames), SMPL22, fps).path
    for first, last in glb_key_times(convert_bvh(bvh, tmp_path / "walk.glb", fps, body=False)):
        assert first == pytest.approx(1 / fps, abs=1e-6) and last == pytest.approx(frames / fps, abs=1e-6)
