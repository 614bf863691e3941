"""The project's mesh video frames (motiondiff.export.mesh_render: matplotlib, face shading by hand) against pyrender
(OpenGL, offscreen) and trimesh (face normals).

    PYOPENGL_PLATFORM=egl /tmp/depvenv/bin/python bench/dependencies/mesh_render.py [--frames 10]

Mesh: an SMPL-sized body of beads (a UV sphere of 6 cm on each of SMPL's 24 rest joints: 6960 vertices,
13 824 triangles; SMPL has 6890 and 13 776) that sways from frame to frame. Frames: the project's `mesh_frames` figure drawn and read back as pixels, against a
pyrender scene (the same mesh rebuilt each frame, a directional light, a perspective camera on the body) rendered
offscreen at the same pixel size. The two are different renderers (a painter's algorithm of flat-shaded faces
against a z-buffer), so faithfulness is not a pixel difference: one frame of each is saved beside the JSON to look
at. Shading: the project's `shade` (normals by a cross product) against the same Lambert formula on trimesh's face
normals. Also recorded: whether pyrender could open an OpenGL context here, and with which platform. Writes
docs/results/dependencies/mesh_render.json and mesh_render_{matplotlib,pyrender}.png.
"""

from __future__ import annotations

import argparse
import inspect
import os
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import OUT_DIR, import_seconds, install_cost, max_abs, require, speed, write  # noqa: E402

from motiondiff.export import mesh_render  # noqa: E402
from motiondiff.geometry.kinematics import forward_kinematics  # noqa: E402
from motiondiff.geometry.skeleton import SMPL24  # noqa: E402

trimesh = require("trimesh")


def bead_body(frames: int) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (frames, V, 3) and faces (F, 3): a sphere per SMPL joint, swaying sideways over the frames."""
    rest = forward_kinematics(np.tile([1.0, 0, 0, 0], (24, 1)), SMPL24.offsets, SMPL24.parents)[0]
    rest[:, 1] += 1.0  # stand on the ground
    sphere = trimesh.creation.uv_sphere(radius=0.06, count=[10, 17])
    verts = np.concatenate([sphere.vertices + j for j in rest])
    faces = np.concatenate([sphere.faces + i * len(sphere.vertices) for i in range(len(rest))])
    sway = 0.15 * np.sin(np.linspace(0, np.pi, frames))[:, None, None] * (verts[None, :, 1:2] / 2.0)
    moved = np.repeat(verts[None], frames, axis=0)
    moved[..., 0] += sway[..., 0]
    return moved, faces.astype(np.int64)


def matplotlib_frames(vertices, faces):
    """A function drawing frame i and returning its RGB pixels, and the pixel size."""
    kw = {"size": 720} if "size" in inspect.signature(mesh_render.mesh_frames).parameters else {}
    fig, draw, _ = mesh_render.mesh_frames(vertices, faces, **kw)

    def frame(i: int) -> np.ndarray:
        draw(i)
        fig.canvas.draw()
        return np.asarray(fig.canvas.buffer_rgba())[..., :3].copy()

    return frame, fig.canvas.get_width_height()


def pyrender_frames(vertices, faces, size: tuple[int, int]):
    """Same, with pyrender offscreen; (None, reason) where no OpenGL context opens."""
    try:
        import pyrender

        renderer = pyrender.OffscreenRenderer(*size)
    except Exception as err:  # noqa: BLE001 (recording why it cannot run here)
        return None, f"{type(err).__name__}: {err}"
    centre = vertices[0].mean(axis=0)
    pose = np.eye(4)
    pose[:3, 3] = centre + np.array([0.0, 0.0, 3.5])  # in front of the body, all of it in view
    light = pyrender.DirectionalLight(intensity=3.0)
    camera = pyrender.PerspectiveCamera(yfov=np.radians(40))

    def frame(i: int) -> np.ndarray:
        scene = pyrender.Scene(bg_color=[1.0, 1.0, 1.0], ambient_light=[0.3, 0.3, 0.3])
        mesh = trimesh.Trimesh(vertices[i], faces, process=False)
        scene.add(pyrender.Mesh.from_trimesh(mesh, smooth=False))
        scene.add(camera, pose=pose)
        scene.add(light, pose=pose)
        colour, _ = renderer.render(scene)
        return colour

    return frame, None


def shading(vertices, faces) -> dict:
    triangles = vertices[0][faces]
    light = mesh_render.light_direction(30.0)

    def ours():
        return mesh_render.shade(triangles, light)

    def theirs():
        normals = trimesh.Trimesh(vertices[0], faces, process=False).face_normals
        return (
            mesh_render.BODY_RGB * (mesh_render.AMBIENT + (1 - mesh_render.AMBIENT) * np.abs(normals @ light))[:, None]
        )

    return {"colour_max_abs_difference": max_abs(ours(), theirs()), **speed(ours, theirs)}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--frames", type=int, default=10, help="frames drawn by each renderer")
    args = parser.parse_args(argv)
    vertices, faces = bead_body(args.frames)
    ours, size = matplotlib_frames(vertices, faces)
    theirs, reason = pyrender_frames(vertices, faces, size)
    result = {"mesh": {"vertices": int(vertices.shape[1]), "faces": int(len(faces))}, "pixels": list(size),
              "pyopengl_platform": os.environ.get("PYOPENGL_PLATFORM", "(unset)"),
              "shading_vs_trimesh_normals": shading(vertices, faces)}  # fmt: skip
    from PIL import Image

    Image.fromarray(ours(args.frames // 2)).save(OUT_DIR / "mesh_render_matplotlib.png")
    if theirs is None:
        result["pyrender"] = f"no OpenGL context: {reason}"
    else:
        Image.fromarray(theirs(args.frames // 2)).save(OUT_DIR / "mesh_render_pyrender.png")
        # frames drawn in turn by each renderer (interleaved), the fastest of each
        result["seconds_per_frame"] = speed(lambda: ours(args.frames // 2), lambda: theirs(args.frames // 2),
                                            repeats=args.frames)  # fmt: skip
    result["size"] = {"pyrender": install_cost("pyrender"), "trimesh": install_cost("trimesh"),
                      "pyrender_import_s": import_seconds("pyrender"), "trimesh_import_s": import_seconds("trimesh")}  # fmt: skip
    result["trimesh_capsule_signature"] = str(inspect.signature(trimesh.creation.capsule)).split(",")[:2]
    write("mesh_render", result)
    print({k: v for k, v in result.items() if k != "size"})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
