"""Why the behaviour study's 3-s wave fails (issue 39): the released Bandai classifier on the first 3, 4.5 s and
the whole of the REAL val/test clips of the waves and of raise-up-right-hand, and the shipped text model's waves
at 3, 4.5 and 6 s (10 samples, its default sampler, seed 0) with their mean joint speed.
    python docs/results/bandai_text/wave_probe/run.py > docs/results/bandai_text/wave_probe/result.md
Needs data/bandai (make data-full)."""

import collections

import numpy as np

from motiondiff.eval.protocol import Evaluators
from motiondiff.model_files.loading import load_model
from motiondiff.model_files.resolve import find_model
from motiondiff.pipelines import MotionPipeline
from motiondiff.studies import behaviour as B

ev = Evaluators.load("checkpoints/evaluators/bandai")
names = ev.action_names


def verdicts(feats) -> str:
    counts = collections.Counter(names[k] for k in B.classify(ev, feats))
    return ", ".join(f"{a} {n}" for a, n in counts.most_common(3))


print("## The classifier on real clips (val + test), cut to their first frames (20 fps)\n")
print("| label | clips | first 60 frames (3 s) | first 90 frames (4.5 s) | whole clip |\n|---|---:|---|---|---|")
for label in ("wave-right-hand", "wave-both-hands", "raise-up-right-hand"):
    feats = []
    for split in ("val", "test"):
        d = np.load(f"data/bandai/{split}.npz", allow_pickle=True)
        i = list(d["action_names"]).index(label)
        off = d["frame_offsets"]
        feats += [d["features"][off[j] : off[j + 1]] for j in np.where(d["action"] == i)[0]]
    cells = [verdicts([f[:n] if n else f for f in feats]) for n in (60, 90, None)]
    print(f"| {label} | {len(feats)} | " + " | ".join(cells) + " |")

module = load_model(find_model("shipped"))
pipe, sampling = MotionPipeline(module), B.default_sampler()
print(f"\n## The shipped model's waves ({sampling}, 10 samples, seed 0)\n")
print("| prompt | seconds | classified as | median mean joint speed m/s |\n|---|---:|---|---:|")
for prompt in ("a person waves the right hand", "waving the right hand."):
    for seconds in (3.0, 4.5, 6.0):
        joints, feats = B.generate(pipe, prompt, seconds, 10, 0, **sampling)
        speed = np.median(B.Behaviour.of(joints, module.hparams.fps).speed)
        print(f"| {prompt} | {seconds:g} | {verdicts(feats)} | {speed:.3f} |")
for frames in (60, 10_000):
    real = B.real_clips("data/bandai", "wave-right-hand", frames, splits=("train",))
    speed = np.median(B.Behaviour.of(real, module.hparams.fps).speed)
    print(f"| real train wave-right-hand clips ({len(real)}) | {'3' if frames == 60 else 'whole'} | | {speed:.3f} |")
