#!/bin/bash
# Runs cells one after another in one background job (one training at a time on a 2-core machine):
#   nohup docs/results/ablation_full/chain.sh text:trans_dec_x0_hml263 action:v_jp ... > outputs/chain.log 2>&1 &
# Each argument is <condition>:<cell>; a finished cell is skipped by cell.sh itself. Stop with kill -9 on this script,
# then on the training's python pid, and add a "stopped by hand" line to the cell's sittings.log.
# On 2 cores two chains side by side, each with OMP_NUM_THREADS=1, train about 20-30 % more steps per hour than one
# chain with two threads (1.49 + 1.53 against 2.3-2.7 steps/s, the trans_dec cell, Xeon @ 2.80 GHz, 2026-12-06).
cd "$(dirname "$0")"
for arg in "$@"; do
  echo "$(date -u +%FT%TZ) chain: ${arg%%:*} ${arg#*:}"
  ./cell.sh "${arg#*:}" "${arg%%:*}"
done
echo "$(date -u +%FT%TZ) chain: done"
