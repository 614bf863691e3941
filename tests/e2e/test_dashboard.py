"""The local dashboards end to end: one 20-step training with `logger=[tensorboard,wandb]` and the evaluation twice
writes TensorBoard events holding the losses, `val/fid` and the sample GIFs; its offline W&B run holds the same
videos (its own record log, read by `wandb leet inspect`); and TensorBoard serving the run draws the loss chart and
plays the GIFs in headless Chromium (skips with the reason without a browser)."""

from __future__ import annotations

import hashlib
import io
import json
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import pytest
from browser_helpers import pixels_near, screenshot
from cli_helpers import REPO, TINY
from fixtures.in_process import run_entry
from PIL import Image

EVALUATORS = REPO / "checkpoints" / "evaluators" / "bandai_mini"
PROMPTS = ["a person walks forward", "a person raises both hands"]  # callbacks.evaluation.videos.prompts (default)
TAGS = ["samples/0_a_person_walks_forward", "samples/1_a_person_raises_both_hands"]
EVALUATION_STEPS = [8, 16]  # 4 steps an epoch, an evaluation every 2nd epoch
RUN_COLOUR = (0xFF, 0x70, 0x43)  # TensorBoard's colour of the first run (its header and sliders are #f57c00)
LEFT_BLUE, RIGHT_RED = (0x1F, 0x77, 0xB4), (0xD6, 0x27, 0x28)  # the renderer's limb colours

pytestmark = pytest.mark.skipif(
    not (EVALUATORS / "text_motion.safetensors").is_file(),
    reason=f"no shipped evaluators in {EVALUATORS}: rebuild them with python -m motiondiff.cli.train_evaluator",
)


@pytest.fixture(scope="module")
def run(tmp_path_factory) -> Path:
    import wandb

    tiny = [o for o in TINY if not o.startswith("logger=")]
    start = time.perf_counter()
    _, out = run_entry("train", tmp_path_factory.mktemp("dashboard"), *tiny, "logger=[tensorboard,wandb]",
                       "trainer.max_steps=20", "trainer.check_val_every_n_epoch=2", "checkpoint_every=100",
                       "callbacks.evaluation.num_clips=8", "callbacks.evaluation.steps=4")  # fmt: skip
    wandb.finish()  # what the end of the `python train.py` process does
    print(f"\n20 training steps, 2 evaluations with their videos: {time.perf_counter() - start:.1f} s")
    return out


def gif_frames(data: bytes) -> int:
    with Image.open(io.BytesIO(data)) as image:
        assert image.format == "GIF"
        return image.n_frames


def test_tensorboard_holds_losses_fid_and_sample_gifs(run):
    from tensorboard.backend.event_processing.event_accumulator import IMAGES, SCALARS, EventAccumulator

    (folder,) = (run / "tensorboard").glob("version_*")
    events = EventAccumulator(str(folder), size_guidance={IMAGES: 0, SCALARS: 0})
    events.Reload()
    tags = events.Tags()
    assert {"train/loss", "val/loss", "val/fid", "val/r_precision_top3"} <= set(tags[SCALARS]), tags[SCALARS]
    assert len(events.Scalars("train/loss")) == 20 and len(events.Scalars("val/fid")) == len(EVALUATION_STEPS)
    assert sorted(tags[IMAGES]) == TAGS
    for tag in TAGS:
        images = events.Images(tag)
        assert [e.step for e in images] == EVALUATION_STEPS  # the steps the weights had (as checkpoint names)
        frames = [gif_frames(e.encoded_image_string) for e in images]
        assert min(frames) > 1, f"{tag}: not animated ({frames} frames)"
        on_disk = run / "videos" / f"step{EVALUATION_STEPS[-1]:07d}" / f"{tag.partition('/')[2]}.gif"
        assert images[-1].encoded_image_string == on_disk.read_bytes()  # the file the CSV log's user finds
    print(f"\nTensorBoard: {len(tags[SCALARS])} scalar tags; GIFs of {frames} frames, "
          f"{images[-1].width}x{images[-1].height} px, {len(images[-1].encoded_image_string) // 1024} KiB")  # fmt: skip


def test_wandb_offline_run_holds_the_same_videos(run):
    """W&B's history rows (read from the run's own record log by `wandb leet inspect`) name each evaluation's videos;
    the media files they point to are the GIFs rendered into the run folder, byte for byte."""
    (offline,) = (run / "wandb").glob("offline-run-*")
    proc = subprocess.run([str(Path(sys.executable).parent / "wandb"), "leet", "inspect", str(offline), "--json"],
                          capture_output=True, text=True, timeout=120)  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-2000:]
    records = [json.loads(line) for line in proc.stdout.splitlines() if line.startswith("{")]
    rows = [r["history"]["item"] for r in records if r.get("type") == "history"]
    videos = [row for row in rows if f"{TAGS[0]}._type" in row]
    assert [int(row["trainer/global_step"]) for row in videos] == EVALUATION_STEPS
    assert any("val/fid" in row for row in rows) and any("train/loss" in row for row in rows)
    for row in videos:
        for tag in TAGS:
            assert row[f"{tag}._type"] == "video-file" and row[f"{tag}.caption"] in PROMPTS
            media = (offline / "files" / row[f"{tag}.path"]).read_bytes()
            rendered = run / "videos" / f"step{int(row['trainer/global_step']):07d}" / f"{tag.partition('/')[2]}.gif"
            assert hashlib.sha256(media).hexdigest() == row[f"{tag}.sha256"]
            assert media == rendered.read_bytes() and gif_frames(media) > 1


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_for_scalars(url: str, server: subprocess.Popen, timeout: float = 60) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        assert server.poll() is None, f"tensorboard exited: {server.stderr.read()[-2000:]}"
        try:
            with urllib.request.urlopen(f"{url}/data/plugin/scalars/tags", timeout=5) as response:
                if any("train/loss" in tags for tags in json.load(response).values()):
                    return
        except OSError:
            pass
        time.sleep(0.5)
    raise AssertionError(f"tensorboard at {url} served no train/loss within {timeout} s")


def test_tensorboard_draws_the_loss_chart_and_plays_the_gifs(browser, run, tmp_path):
    port = free_port()
    url = f"http://127.0.0.1:{port}"
    server = subprocess.Popen([sys.executable, "-m", "tensorboard.main", "--logdir", str(run / "tensorboard"),
                               "--host", "127.0.0.1", "--port", str(port)],
                              stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)  # fmt: skip
    try:
        wait_for_scalars(url, server)
        scalars = screenshot(browser, f"{url}/#scalars&tagFilter=train%2Floss", tmp_path / "scalars.png", "1000,800")
        images = screenshot(browser, f"{url}/#images", tmp_path / "images.png", "1000,800")
    finally:
        server.terminate()
        server.wait(timeout=30)
    # below the orange header bar, right of the settings column: the charts and images
    line = pixels_near(scalars[180:, 280:], RUN_COLOUR, tol=20)
    blue, red = pixels_near(images[180:, 280:], LEFT_BLUE), pixels_near(images[180:, 280:], RIGHT_RED)
    print(f"\nTensorBoard in Chromium: {line} pixels of the loss curves; the GIF's limbs {blue} blue, {red} red")
    assert line > 300, f"the Scalars page drew no train/loss curve ({line} pixels of its colour); see {tmp_path}"
    assert blue > 50 and red > 50, f"the Images page shows no stick figure ({blue} blue, {red} red); see {tmp_path}"


def test_action_model_videos_show_its_first_actions(action_ckpt, tmp_path):
    from motiondiff.eval.sample_videos import SampleVideos, slug
    from motiondiff.model_files.loading import load_model

    module = load_model(action_ckpt)
    videos = SampleVideos(seconds=1.0).render(module, tmp_path, guidance=module.default_guidance)
    names = list(module.hparams.action_names[:2])  # videos.actions=null: the model's first `count`
    assert [caption for _, _, caption in videos] == names
    assert [tag for tag, _, _ in videos] == [f"samples/{k}_{slug(name)}" for k, name in enumerate(names)]
    assert all(gif_frames(path.read_bytes()) > 1 for _, path, _ in videos)
