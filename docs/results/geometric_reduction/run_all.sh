#!/bin/bash
# rules.md beside this file, end to end and resumable: R0 (the ablation cell, cell.sh) and R1 (r1.sh) each stopped
# after their step-2,000 checkpoint, then both measured on val. The R0 cell's later sittings go on from there.
set -u
cd "$(dirname "$0")/../../.."
here=docs/results/geometric_reduction
r0=outputs/ablation_full/action_x0_hml263/checkpoints/step0002000.ckpt
r1=outputs/geometric_reduction/r1/checkpoints/step0002000.ckpt
source docs/results/sittings.sh  # until_checkpoint
until_checkpoint $r0 outputs/geometric_r0.log docs/results/ablation_full/cell.sh x0_hml263 action || exit 1
grep -q "stopped after its step-2,000" docs/results/ablation_full/cells/action_x0_hml263/sittings.log || \
  echo "$(date -u +%FT%TZ) sitting stopped after its step-2,000 checkpoint (docs/results/geometric_reduction/rules.md: R0)" \
  >> docs/results/ablation_full/cells/action_x0_hml263/sittings.log
until_checkpoint $r1 outputs/geometric_r1.log $here/r1.sh || exit 1
[ -f $here/val/R0.json ] || $here/measure.sh $r0 R0
[ -f $here/val/R1.json ] || $here/measure.sh $r1 R1
echo done
