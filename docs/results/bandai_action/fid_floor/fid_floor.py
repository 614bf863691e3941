"""The action FID a perfect generator would score on the Bandai val and test splits (issue 39's action target).

The evaluation compares the generated motions (one per real clip of the split, with its action label and length)
with the split's real clips, so both sides are small samples (276/277) and the FID is biased upward even for a
generator that draws from the true distribution. This script measures that bias with real motion only: for each
clip of the split it draws a random real train clip of the same action (the generator conditioned on the label,
made perfect), embeds it with the released action classifier as the evaluation of the shipped action model does
(clips cropped to its MAX_FRAMES, cut to the unit length), and scores FID against the split's real clips. Repeated
over REPS draws: mean ± 95 % interval as the evaluation tables give it (`eval.report.mean_ci`). Nothing here is
chosen or trained; the test clips are read only as the evaluation's reference.

    .venv/bin/python docs/results/bandai_action/fid_floor/fid_floor.py > docs/results/bandai_action/fid_floor/README.md
"""

import sys

import numpy as np

import motiondiff.metrics as M
from motiondiff.data.datamodules import PreparedDataModule
from motiondiff.eval.protocol import EvalClips, Evaluators
from motiondiff.eval.report import mean_ci
from motiondiff.runtime.hardware import cpu_model

REPS = 20
MAX_FRAMES = 120  # the shipped action model's max_frames: evaluate.py crops every split's clips to it


def main() -> None:
    dm = PreparedDataModule("data/bandai", batch_size=64, max_frames=MAX_FRAMES)
    dm.setup("fit")
    evaluators = Evaluators.load("checkpoints/evaluators/bandai", num_joints=22)
    key = evaluators.fid_features("action")
    train = EvalClips.from_dataset(dm.dataset("train"))
    train_emb = evaluators.embed_motion(train.features)[key]
    by_action = {a: np.flatnonzero(train.actions == a) for a in np.unique(train.actions)}
    print(f"`{' '.join(sys.argv)}` ({cpu_model()}): the released action classifier's "
          f"features, {REPS} draws, mean ± 95 % CI as in the evaluation tables.\n")  # fmt: skip
    print("| split | clips | real split vs real train (the table's Real row) | perfect generator: same-action train "
          "clips vs the split's real clips | ratio |")  # fmt: skip
    print("|---|---:|---:|---:|---:|")
    for split in ("val", "test"):
        clips = EvalClips.from_dataset(dm.dataset(split))
        real = evaluators.embed_motion(clips.features)[key]
        real_row = M.frechet_distance(*M.gaussian_statistics(train_emb), *M.gaussian_statistics(real))
        rng, fids = np.random.default_rng(0), []
        for _ in range(REPS):
            drawn = np.array([rng.choice(by_action[a]) for a in clips.actions])
            fids.append(M.frechet_distance(*M.gaussian_statistics(real), *M.gaussian_statistics(train_emb[drawn])))
        mean, half = mean_ci(fids)
        print(f"| {split} | {len(clips)} | {real_row:.3f} | {mean:.3f} ± {half:.3f} | {mean / real_row:.2f} |")


if __name__ == "__main__":
    main()
