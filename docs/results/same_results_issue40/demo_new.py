import sys, numpy as np
from motiondiff.demo.inputs import Sampling
from motiondiff.demo.models import DemoModels
from motiondiff.demo.modes.generate import generate
m = DemoModels(blender=False)
print([c.key for c in m.choices])
out = generate(m, "action", "wave-right-hand", seconds=2.0, sampling=Sampling(seed=3, steps=10, num_samples=2, guidance=2.0))
np.save(sys.argv[1], np.stack(out.joints))
