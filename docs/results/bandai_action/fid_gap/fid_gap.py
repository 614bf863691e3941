"""Where the shipped action model's FID gap sits, on the Bandai **val** split (issue 39's action target, 0.09).

The model's val FID (about 0.11) is twice a perfect generator's (0.053, ../fid_floor/). This script generates the
val split as the evaluation does (one motion per real clip, its label and length; DDIM-50, guidance 2) and splits
the FID in two ways, to say which change could close the gap:
- the Fréchet distance's two terms: the squared distance of the means and the covariance term;
- "repair" per action and per length: the generated motions of one action (or one length bin) are replaced by
  random real train clips of the same action, as a perfect generator would give them, and the FID is taken again
  (mean over DRAWS draws). The drop is that group's share of the gap.
Val only: nothing here touches the test split, and the numbers choose nothing by themselves.

    .venv/bin/python docs/results/bandai_action/fid_gap/fid_gap.py [checkpoint] > docs/results/bandai_action/fid_gap/<name>.md
"""

import sys
import time
from pathlib import Path

import numpy as np
import torch

import motiondiff.metrics as M
from motiondiff.data.datamodules import PreparedDataModule
from motiondiff.eval.protocol import EvalClips, Evaluators, generate
from motiondiff.lit.generation import feed_forward_shape
from motiondiff.model_files.loading import load_model
from motiondiff.runtime.hardware import cpu_model, inference_precision

CHECKPOINT = "checkpoints/models/bandai_action_trans_dec_14k.safetensors"
REPLICATIONS, DRAWS = 2, 10
TOLERANCE = 16  # frames (4 of the evaluators' 4-frame units)
LENGTH_BINS = [(0, 60), (60, 100), (100, 1000)]


def fid(a: np.ndarray, b: np.ndarray) -> float:
    return M.frechet_distance(*M.gaussian_statistics(a), *M.gaussian_statistics(b))


def mean_term(real: np.ndarray, gen: np.ndarray) -> float:
    """The Fréchet distance's squared distance of the means (the rest of it is the covariance term)."""
    return float(((real.mean(0) - gen.mean(0)) ** 2).sum())


def perfect_draws(evaluators, key, records, actions, lengths, rng, max_frames, anywhere=False) -> list[np.ndarray]:
    """DRAWS embeddings of a perfect generator, asked as the model is (action and length): for each val row a random
    train clip of its action whose length (cropped to `max_frames`, as the evaluation crops) is within TOLERANCE
    frames of the row's, else the nearest lengths; its first frames, as the evaluation cuts every clip, or with
    `anywhere` a window of the row's length at a random start, as training draws them."""
    train_actions = np.array([r.action for r in records])
    train_len = np.array([min(r.length, max_frames) for r in records])
    pools = {}
    for a, n in set(zip(actions.tolist(), lengths.tolist(), strict=True)):
        same = np.flatnonzero(train_actions == a)
        gap = np.abs(train_len[same] - n)
        pools[a, n] = same[gap <= max(TOLERANCE, gap.min())]
    out = []
    for _ in range(DRAWS):
        clips = []
        for a, n in zip(actions.tolist(), lengths.tolist(), strict=True):
            motion = records[rng.choice(pools[a, n])].motion
            start = int(rng.integers(0, max(len(motion) - n, 0) + 1)) if anywhere else 0
            clips.append(motion[start : start + n].astype(np.float32))
        out.append(evaluators.embed_motion(clips)[key])
    return out


def repaired(gen, real, draws, mask) -> float:
    """FID after the rows in `mask` are replaced by a perfect generator's rows, mean over its draws."""
    out = []
    for d in draws:
        g = gen.copy()
        g[mask] = d[mask]
        out.append(fid(real, g))
    return float(np.mean(out))


def main() -> None:
    ckpt = sys.argv[1] if len(sys.argv) > 1 else CHECKPOINT
    module = load_model(ckpt, "cpu")
    max_frames = int(module.hparams.max_frames)
    precision = inference_precision("auto", "cpu", feed_forward_shape(module, 64, max_frames))
    dm = PreparedDataModule("data/bandai", batch_size=64, max_frames=max_frames)
    dm.setup("fit")
    evaluators = Evaluators.load("checkpoints/evaluators/bandai", num_joints=22).for_module(module)
    key = evaluators.fid_features("action")
    names = evaluators.action_names
    train = EvalClips.from_dataset(dm.dataset("train"))
    val = EvalClips.from_dataset(dm.dataset("val"))
    real = evaluators.embed_motion(val.features)[key]
    actions, lengths = val.actions, val.lengths.numpy()
    train_counts = {a: int((train.actions == a).sum()) for a in np.unique(train.actions)}
    records = dm.dataset("train").records
    draws = perfect_draws(evaluators, key, records, actions, lengths, np.random.default_rng(0), max_frames)
    floor = repaired(real, real, draws, np.ones(len(real), bool))
    windows = perfect_draws(evaluators, key, records, actions, lengths, np.random.default_rng(2), max_frames, True)
    anywhere = repaired(real, real, windows, np.ones(len(real), bool))
    whole = np.random.default_rng(1)  # ../fid_floor/'s draws: any same-action train clip, whatever its length
    pool = {a: np.flatnonzero(train.actions == a) for a in np.unique(actions)}
    unmatched = float(
        np.mean(
            [
                fid(real, evaluators.embed_motion([train.features[whole.choice(pool[a])] for a in actions])[key])
                for _ in range(DRAWS)
            ]
        )
    )

    # the generated embeddings, reused on a rerun of the same file (named by its whole path: runs share last.ckpt)
    cache = Path("outputs/fid_gap") / (str(Path(ckpt).with_suffix("")).strip("/").replace("/", "__") + ".npz")
    start, gens, preds = time.perf_counter(), [], []
    if cache.exists():
        saved = np.load(cache)
        gens, preds, reused = list(saved["gens"]), list(saved["preds"]), len(saved["gens"])
    else:
        reused = 0
    for r in range(len(gens), REPLICATIONS):
        generator = torch.Generator().manual_seed(r)
        feats = generate(module, [int(a) for a in actions], val.lengths, 64, generator, precision=precision,
                         guidance=2.0, sampler="ddim", steps=50, eta=0.0)  # fmt: skip
        emb = evaluators.embed_motion(feats)
        gens.append(emb[key])
        preds.append(emb["action_logits"].argmax(-1))
    minutes = (time.perf_counter() - start) / 60
    cache.parent.mkdir(parents=True, exist_ok=True)
    np.savez(cache, gens=np.stack(gens), preds=np.stack(preds))

    print(f"`{' '.join(sys.argv)}`: {ckpt}, val split ({len(val)} clips, cropped to {max_frames} frames), "
          f"{REPLICATIONS} replications, DDIM-50, guidance 2, {precision}; repairs averaged over {DRAWS} draws of "
          f"same-action train clips. {cpu_model()}, {minutes:.1f} min of generation"
          f"{f' ({reused} replication(s) read back from {cache})' if reused else ''}.\n")  # fmt: skip
    total = [fid(real, g) for g in gens]
    means = np.mean([mean_term(real, g) for g in gens])
    gap = np.mean(total) - floor
    print(f"FID {np.mean(total):.3f} (replications {', '.join(f'{t:.3f}' for t in total)}); a perfect generator "
          f"(every row repaired: a same-action train clip within {TOLERANCE} frames of its length) {floor:.3f} "
          f"(with whole train clips, as ../fid_floor/ draws them: {unmatched:.3f}; with windows at a random start, "
          f"as training draws them: {anywhere:.3f}); the gap {gap:.3f}. Squared mean distance {means:.3f}, "
          f"covariance term {np.mean(total) - means:.3f}.\n")  # fmt: skip

    print("| action | val clips | train clips | accuracy | FID with this action repaired | share of the gap |")
    print("|---|---:|---:|---:|---:|---:|")
    rows = []
    for a in np.unique(actions):
        mask = actions == a
        after = np.mean([repaired(g, real, draws, mask) for g in gens])
        acc = np.mean([(p[mask] == a).mean() for p in preds])
        rows.append((np.mean(total) - after, a, mask.sum(), acc, after))
    for drop, a, n, acc, after in sorted(rows, reverse=True):
        print(f"| {names[a]} | {n} | {train_counts.get(a, 0)} | {acc:.2f} | {after:.3f} | {drop / gap:+.0%} |")

    print("\n| length (frames) | val clips | FID with this bin repaired | share of the gap |")
    print("|---|---:|---:|---:|")
    for lo, hi in LENGTH_BINS:
        mask = (lengths >= lo) & (lengths < hi)
        after = np.mean([repaired(g, real, draws, mask) for g in gens])
        print(f"| {lo}-{min(hi, max_frames)} | {mask.sum()} | {after:.3f} | {(np.mean(total) - after) / gap:+.0%} |")


if __name__ == "__main__":
    main()
