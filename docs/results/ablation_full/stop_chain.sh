#!/bin/bash
# Stops the chain that is training one cell, right after that cell's next step checkpoint, and says so in the cell's
# sittings.log (the next sitting resumes from that checkpoint; at most a few steps are lost):
#   docs/results/ablation_full/stop_chain.sh <condition>_<cell> "<why>"      e.g. action_v_jp "session end"
# It kills (kill -9: background jobs ignore SIGINT) the chain.sh running the cell, its cell.sh and the training, then
# copies the sitting's curves as cell.sh would have. Start the chain again with the same arguments to go on.
set -u
cd "$(dirname "$0")/../../.."; source docs/results/sittings.sh
NAME=$1; WHY=${2:-stopped by hand}; COND=${NAME%%_*}; CELL=${NAME#*_}
RUN=outputs/ablation_full/$NAME; CELLDIR=docs/results/ablation_full/cells/$NAME
train=$(pgrep -f "train.py .*hydra.run.dir=$RUN( |$)" | head -1)
cell=$(pgrep -f "cell.sh $CELL $COND$" | head -1)
[ -n "$train" ] && [ -n "$cell" ] || { echo "no training of $NAME is running"; exit 1; }
chain=$(ps -o ppid= -p "$cell" | xargs)
newest() { ls -t $RUN/checkpoints/step*.ckpt 2>/dev/null | head -1; }
before=$(newest)
echo "$(date -u +%T) waiting for $NAME's next step checkpoint (newest now: ${before:-none})"
while [ "$(newest)" == "$before" ]; do
  kill -0 "$train" 2>/dev/null || { echo "the training of $NAME ended by itself"; exit 1; }
  sleep 10
done
ckpt=$(newest); last=$RUN/checkpoints/last.ckpt
until_written "$ckpt"
# last.ckpt (where the next sitting resumes) is written after the step file: wait until it is as new and complete
while [ ! "$last" -nt "$ckpt" ] && [ "$(stat -c %Y "$last")" != "$(stat -c %Y "$ckpt")" ]; do sleep 5; done
until_written "$last"
kill -9 "$chain" "$cell" "$train" 2>/dev/null
step=$(basename "$ckpt" .ckpt | sed 's/^step0*//' | sed ':a;s/\B[0-9]\{3\}\>/,&/;ta')
echo "$(date -u +%FT%TZ) sitting stopped by hand after its step-$step checkpoint ($WHY)" >> "$CELLDIR/sittings.log"
copy_cell_curves "$RUN" "$CELLDIR"
echo "$(date -u +%T) stopped $NAME after step $step (chain $chain, cell.sh $cell, training $train)"
