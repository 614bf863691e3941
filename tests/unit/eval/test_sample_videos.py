"""eval.sample_videos: the TensorBoard GIF summary (written with torch's SummaryWriter, read back by TensorBoard's
own event reader, still an animated GIF), and the checks of the `callbacks.evaluation.videos` settings."""

from __future__ import annotations

import io
from types import SimpleNamespace

import numpy as np
import pytest
from PIL import Image

from motiondiff.eval.sample_videos import SampleVideos, add_gif, gif_summary, slug
from motiondiff.runtime.errors import UsageError


def animated_gif(frames: int = 3, size: tuple[int, int] = (24, 16)) -> bytes:
    """A real GIF whose frames differ (a bar moving to the right)."""
    images = []
    for k in range(frames):
        pixels = np.full((size[1], size[0], 3), 255, np.uint8)
        pixels[:, 4 * k : 4 * k + 4] = (214, 39, 40)
        images.append(Image.fromarray(pixels))
    out = io.BytesIO()
    images[0].save(out, format="GIF", save_all=True, append_images=images[1:], duration=100, loop=0)
    return out.getvalue()


def test_gif_round_trips_through_tensorboard_events(tmp_path):
    from tensorboard.backend.event_processing.event_accumulator import IMAGES, EventAccumulator
    from torch.utils.tensorboard import SummaryWriter

    gif = animated_gif()
    (tmp_path / "clip.gif").write_bytes(gif)
    writer = SummaryWriter(log_dir=str(tmp_path / "events"))
    add_gif(writer, "samples/0_a_person_walks", tmp_path / "clip.gif", step=7)
    add_gif(writer, "samples/0_a_person_walks", tmp_path / "clip.gif", step=9)
    writer.close()

    events = EventAccumulator(str(tmp_path / "events"), size_guidance={IMAGES: 0})
    events.Reload()
    assert events.Tags()[IMAGES] == ["samples/0_a_person_walks"]
    written = events.Images("samples/0_a_person_walks")
    assert [e.step for e in written] == [7, 9]
    assert (written[0].width, written[0].height) == (24, 16)
    assert written[0].encoded_image_string == gif  # the bytes themselves: TensorBoard serves them as image/gif
    with Image.open(io.BytesIO(written[0].encoded_image_string)) as image:
        assert image.format == "GIF" and image.n_frames == 3


def test_gif_summary_refuses_other_images():
    out = io.BytesIO()
    Image.new("RGB", (4, 4)).save(out, format="PNG")
    with pytest.raises(ValueError, match="expected GIF bytes, got PNG"):
        gif_summary("samples/x", out.getvalue())


def test_settings_from_config():
    assert SampleVideos.from_config(None) is None  # videos: null
    videos = SampleVideos.from_config({"prompts": "a person waves", "steps": 4}, seed=3)
    assert videos.prompts == ["a person waves"] and videos.steps == 4 and videos.seed == 3
    with pytest.raises(UsageError, match=r"callbacks\.evaluation\.videos\.count=0: must be an integer from 1 to 8"):
        SampleVideos.from_config({"count": 0})
    with pytest.raises(UsageError, match=r"videos\.seconds='long': must be a number"):
        SampleVideos.from_config({"seconds": "long"})
    with pytest.raises(UsageError, match=r"videos\.frames is not a setting; the settings are prompts, actions"):
        SampleVideos.from_config({"frames": 40})
    assert SampleVideos().size == 160  # small: logged at every evaluation
    with pytest.raises(UsageError, match=r"videos\.size=161: .*even whole number from 64 to 2160"):
        SampleVideos.from_config({"size": 161})


def test_conditions_fit_the_model():
    text = SimpleNamespace(condition_kind="text", hparams=SimpleNamespace(action_names=None))
    action = SimpleNamespace(condition_kind="action", hparams=SimpleNamespace(action_names=["walk", "run", "bow"]))
    none = SimpleNamespace(condition_kind="none", hparams=SimpleNamespace(action_names=None))
    assert SampleVideos(prompts=["a person runs"]).conditions(text) == ["a person runs"]
    assert SampleVideos(count=2).conditions(action) == ["walk", "run"]  # the model's first actions
    assert SampleVideos(actions=["bow"]).conditions(action) == ["bow"]
    assert SampleVideos(count=3).conditions(none) == [None, None, None]
    with pytest.raises(UsageError, match="no action 'jump'; its actions are walk, run, bow"):
        SampleVideos(actions=["jump"]).conditions(action)
    with pytest.raises(UsageError, match=r"videos\.prompts must list 1 to 8 texts"):
        SampleVideos(prompts=[]).conditions(text)


def test_slug_names_tags_and_files():
    assert slug("A person walks, then waves!") == "a_person_walks_then_waves"
    assert slug(None) == "unconditioned" and slug("wave-right-hand") == "wave_right_hand"
