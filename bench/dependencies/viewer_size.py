"""What a motion's HTML viewer file costs with each way of drawing it: the project's own script
(src/motiondiff/assets/motion_viewer.js), plotly.js (what the viewer embedded before) and three.js bundled with only
what a skeleton viewer needs (a WebGL renderer, a camera, line segments, a grid, spheres), minified.

    /tmp/depvenv/bin/python bench/dependencies/viewer_size.py

three.js is fetched from the npm registry into a temporary folder and bundled by esbuild (tree-shaken, minified);
needs npm. Issue 42 asks for at most 300 KB per motion file. Writes docs/results/dependencies/viewer_size.json.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import REPO, write  # noqa: E402

THREE, ESBUILD = "three@0.187.0", "esbuild@0.25"
ENTRY = """import {WebGLRenderer, Scene, PerspectiveCamera, LineSegments, BufferGeometry, LineBasicMaterial,
  Float32BufferAttribute, GridHelper, SphereGeometry, Mesh, MeshBasicMaterial} from 'three';
const renderer = new WebGLRenderer(); const scene = new Scene(); const camera = new PerspectiveCamera(50, 1, 0.1, 100);
const bones = new BufferGeometry(); bones.setAttribute('position', new Float32BufferAttribute([0, 0, 0, 1, 1, 1], 3));
scene.add(new LineSegments(bones, new LineBasicMaterial())); scene.add(new GridHelper(10, 10));
scene.add(new Mesh(new SphereGeometry(0.1), new MeshBasicMaterial())); renderer.render(scene, camera);
"""


def three_bundle_bytes() -> dict:
    if shutil.which("npm") is None:
        return {"skipped": "npm not found"}
    with tempfile.TemporaryDirectory() as tmp:
        run = {"cwd": tmp, "check": True, "capture_output": True, "text": True, "timeout": 600}
        subprocess.run(["npm", "init", "-y"], **run)
        subprocess.run(["npm", "install", "--no-audit", "--no-fund", THREE, ESBUILD], **run)
        (Path(tmp) / "entry.mjs").write_text(ENTRY)
        subprocess.run(["npx", "esbuild", "entry.mjs", "--bundle", "--minify", "--format=iife",
                        "--outfile=bundle.min.js"], **run)  # fmt: skip
        version = json.loads((Path(tmp) / "node_modules" / "three" / "package.json").read_text())["version"]
        return {"version": version, "bytes": (Path(tmp) / "bundle.min.js").stat().st_size}


def main() -> int:
    import plotly

    own = REPO / "src" / "motiondiff" / "assets" / "motion_viewer.js"
    plotly_js = Path(plotly.__file__).parent / "package_data" / "plotly.min.js"
    result = {
        "project_motion_viewer_js_bytes": own.stat().st_size if own.is_file() else None,
        "plotly_min_js_bytes": plotly_js.stat().st_size if plotly_js.is_file() else None,
        "plotly_version": plotly.__version__,
        "three_minimal_bundle": three_bundle_bytes(),
        "budget_per_motion_file_bytes": 300_000,
    }
    write("viewer_size", result)
    print(result)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
