"""Write the sampler, steps and guidance chosen on val (summary.md) into a release's JSON, so sample.py, the API,
the demo and the studies use them; the weights are written back unchanged (their checksum is checked equal).

    python docs/results/recipe_search/sampler_guidance/apply.py <release> <sampler> <steps> <guidance> "<note>"
"""

import sys

from motiondiff.model_files.release import load_release, provenance_of, save_release
from motiondiff.model_files.release_checks import read_release_json, release_paths

release, sampler, steps, guidance, note = sys.argv[1:6]
before = read_release_json(release_paths(release)[1])["weights_sha256"]
module = load_release(release)
module.hparams.model.update(sample_sampler=sampler, sample_steps=int(steps), sample_guidance=float(guidance))
provenance = {**provenance_of(release), "default_sampler": note}
save_release(module, release, provenance)
after = read_release_json(release_paths(release)[1])["weights_sha256"]
assert before == after, "the weights changed"
print(f"{release}: {sampler}-{steps}, guidance {guidance}; weights unchanged ({after[:12]})")
