import sys, tempfile, numpy as np
from motiondiff.demo.models import DemoModels, generate
m = DemoModels()
print([c.key for c in m.choices])
out, _ = generate(m, "action", "wave-right-hand", tempfile.mkdtemp(), seconds=2.0, seed=3, num_samples=2, steps=10, guidance=2.0)
np.save(sys.argv[1], np.stack(out.joints))
