"""sample.py render=mesh (in process, the released text model, a synthetic SMPL body model of the real layout): the
GIF shows the body's mesh, and every way to get the option wrong is one clear error before any sampling, with
nothing written."""

from __future__ import annotations

import json

import numpy as np
from fixtures.in_process import files_under, run_entry, user_error
from fixtures.synthetic_smpl import write_synthetic_smpl
from PIL import Image

SAMPLE = ["checkpoint=shipped", "num_samples=1", "steps=3", "length=2", "text=a person walks"]


def test_sample_writes_a_mesh_gif(tmp_path):
    model = write_synthetic_smpl(tmp_path / "SMPL_NEUTRAL.npz", sphere=(6, 8))
    _, out = run_entry("sample", tmp_path, *SAMPLE, "export=[gif]", "render=mesh", f"smpl_model={model}")
    row = json.loads((out / "results.json").read_text())["samples"][0]
    video = Image.open(row["exports"]["gif"])
    assert video.n_frames == len(np.load(row["joints"])) == 40
    rgb = np.asarray(video.convert("RGB")).astype(float) / 255
    mesh = (rgb.max(-1) < 0.8) & (rgb.max(-1) - rgb.min(-1) < 0.06)  # gray, darker than the ground grid
    limbs = (np.abs(rgb - np.array([0x1F, 0x77, 0xB4]) / 255).max(-1) < 0.12).sum()  # the stick figure's blue
    assert 0.02 < mesh.mean() < 0.3 and limbs == 0


def test_render_mistakes_are_one_error_before_sampling(tmp_path):
    model = write_synthetic_smpl(tmp_path / "SMPL_NEUTRAL.npz")
    (tmp_path / "broken.npz").write_bytes(b"not a zip")
    cases = [
        (["render=mesh"], "licence-restricted and not shipped: register at smpl.is.tue.mpg.de"),
        (["render=mesh", f"smpl_model={tmp_path / 'broken.npz'}"], "not a readable .npz of plain arrays"),
        (["render=mesh", f"smpl_model={tmp_path / 'missing.npz'}"], "not found"),
        (["render=solid"], "unknown render='solid': choose stick"),
        ([f"smpl_model={model}"], "is the body of render=mesh videos: add render=mesh"),
        (["render=mesh", f"smpl_model={model}", "export=[bvh]"], "export=bvh has none: add mp4 or gif to export="),
    ]
    for k, (overrides, message) in enumerate(cases):
        folder = tmp_path / f"case{k}"
        error = user_error("sample", folder, *SAMPLE, *overrides)
        assert message in error and "\n" not in error, (overrides, error)
        assert not files_under(folder / "run"), overrides
