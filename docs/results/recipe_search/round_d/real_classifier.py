"""The Bandai action classifier on the real val and test clips (first 120 frames), per action, pooled."""
import numpy as np
from collections import defaultdict
from motiondiff.eval.protocol import Evaluators
from motiondiff.data.formats.prepared import load_split
ev = Evaluators.load('checkpoints/evaluators/bandai', 22)
names = ev.action_names
per = defaultdict(lambda: [0, 0])
for split in ['val', 'test']:
    d = load_split('data/bandai', split)
    feats = [d.arrays['features'][d.feature_slice(i)][:120] for i in range(d.num_clips)]
    pred = ev.embed_motion(feats)['action_logits'].argmax(-1)
    for i in range(d.num_clips):
        a = d.label('content', i)
        per[a][0] += int(names[pred[i]] == a); per[a][1] += 1
for a in sorted(per, key=lambda a: per[a][1]):
    print(f"{a:22s} {per[a][0]}/{per[a][1]}")
