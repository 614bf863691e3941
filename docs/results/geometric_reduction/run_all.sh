#!/bin/bash
# rules.md beside this file, end to end and resumable: R0 (the ablation cell, cell.sh) and R1 (r1.sh) each stopped
# after their step-2,000 checkpoint, then both measured on val. The R0 cell's later sittings go on from there.
set -u
cd "$(dirname "$0")/../../.."
here=docs/results/geometric_reduction
r0=outputs/ablation_full/action_x0_hml263/checkpoints/step0002000.ckpt
r1=outputs/geometric_reduction/r1/checkpoints/step0002000.ckpt
source docs/results/sittings.sh  # until_checkpoint, cell_until_step
cell_until_step x0_hml263 action 0002000 "docs/results/geometric_reduction/rules.md: R0" || exit 1
until_checkpoint $r1 outputs/geometric_r1.log $here/r1.sh || exit 1
[ -f $here/val/R0.json ] || $here/measure.sh $r0 R0
[ -f $here/val/R1.json ] || $here/measure.sh $r1 R1
echo done
