#!/bin/bash
# Runs cells one after another in one background job (one training at a time on a 2-core machine):
#   nohup docs/results/ablation_full/chain.sh text:trans_dec_x0_hml263 action:v_jp ... > outputs/chain.log 2>&1 &
# Each argument is <condition>:<cell>; a finished cell is skipped by cell.sh itself. Stop with kill -9 on the
# training's python pid, then kill this script (cell.sh logs the sitting's end either way).
cd "$(dirname "$0")"
for arg in "$@"; do
  echo "$(date -u +%FT%TZ) chain: ${arg%%:*} ${arg#*:}"
  ./cell.sh "${arg#*:}" "${arg%%:*}"
done
echo "$(date -u +%FT%TZ) chain: done"
