"""Is the sampler why the shipped model's waves are still? "a person waves the right hand" at 6 s, 10 samples, seed 0,
under five samplers/guidances: the classifier's verdicts and the median mean joint speed (real train waves: 0.09 m/s).
    python docs/results/bandai_text/wave_probe/samplers.py > docs/results/bandai_text/wave_probe/samplers.txt"""

import collections

import numpy as np
import torch

from motiondiff.eval.protocol import Evaluators
from motiondiff.model_files.loading import load_model
from motiondiff.model_files.resolve import find_model
from motiondiff.pipelines import MotionPipeline
from motiondiff.studies import behaviour as B

torch.set_num_threads(1)  # it ran beside a training

m = load_model(find_model("shipped"))
ev = Evaluators.load("checkpoints/evaluators/bandai")
names = ev.action_names
pipe = MotionPipeline(m)
for samp in [
    dict(sampler="dpmpp", steps=10),
    dict(sampler="ddim", steps=50),
    dict(sampler="ddim", steps=50, guidance=3.0),
    dict(sampler="dpmpp", steps=10, guidance=3.0),
    dict(sampler="ddpm", steps=None),
]:
    j, f = B.generate(pipe, "a person waves the right hand", 6.0, 10, 0, **samp)
    p = B.classify(ev, f)
    print(
        samp,
        collections.Counter(names[i] for i in p).most_common(2),
        "speed",
        round(float(np.median(B.Behaviour.of(j, m.hparams.fps).speed)), 3),
        flush=True,
    )
