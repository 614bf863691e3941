"""Rule of "The run's end", step 2 (docs/results/recipe_search/rules.md): the highest val action accuracy (label
captions) wins; within 0.01 of it the lower val FID. Reads every <sampler><steps>_g<guidance>/metrics.json under the
folder given and prints the table and the pick as Markdown."""

import json
import sys
from pathlib import Path

rows = []
for path in sorted(Path(sys.argv[1]).glob("*/metrics.json")):
    m = json.loads(path.read_text())
    s = m["summary"]
    rows.append({"sampler": f"{m['sampler']['name']}-{m['steps']}", "guidance": m["guidance"],
                 "acc": s["action_accuracy"][:2], "acc_random": s["action_accuracy_random"][:2], "fid": s["fid"][:2],
                 "rprec3": s["r_precision_top3"][:2], "wall_s": m["wall_s"]})  # fmt: skip
best_acc = max(r["acc"][0] for r in rows)
pick = min((r for r in rows if r["acc"][0] >= best_acc - 0.01), key=lambda r: r["fid"][0])
print("| sampler | guidance | action acc. (label) | action acc. (random) | FID | R-prec top-3 | wall s |")
print("|---|---:|---:|---:|---:|---:|---:|")
for r in sorted(rows, key=lambda r: (r["sampler"], r["guidance"])):
    mark = "**" if r is pick else ""
    print(f"| {mark}{r['sampler']}{mark} | {r['guidance']:g} | {r['acc'][0]:.3f} ± {r['acc'][1]:.3f} | "
          f"{r['acc_random'][0]:.3f} ± {r['acc_random'][1]:.3f} | {r['fid'][0]:.3f} ± {r['fid'][1]:.3f} | "
          f"{r['rprec3'][0]:.3f} ± {r['rprec3'][1]:.3f} | {r['wall_s']:.0f} |")  # fmt: skip
print(
    f"\nHighest accuracy {best_acc:.3f}; within 0.01 of it the lowest FID: **{pick['sampler']}, guidance "
    f"{pick['guidance']:g}** (FID {pick['fid'][0]:.3f})."
)
