# Sourced by the scripts that train in sittings (final_run.sh, bandai_action/*/run.sh, ablation_full/cell.sh,
# eps_fix/ and geometric_reduction/run_all.sh,
# guidedmotion/mirror_release/run.sh): tcmalloc where it is installed, where a sitting resumes from, and its log line.

# Training runs with tcmalloc where Debian's is installed (see the Makefile's WITH_TCMALLOC).
use_tcmalloc() {
  local lib; lib=$(ls /usr/lib/*/libtcmalloc_minimal.so.4 2>/dev/null | head -1)
  [ -n "$lib" ] && export LD_PRELOAD=$lib
  return 0
}

# resume_arg RUN [SITTING]: "ckpt_path=RUN/checkpoints/last.ckpt" when the run folder has one, after copying it from
# the committed sitting checkpoint SITTING on a machine whose folder lacks it; empty for a run that starts afresh.
resume_arg() {
  local run=$1 sitting=${2:-}
  if [ ! -f "$run/checkpoints/last.ckpt" ] && [ -n "$sitting" ] && [ -f "$sitting" ]; then
    mkdir -p "$run/checkpoints" && cp "$sitting" "$run/checkpoints/last.ckpt"
  fi
  [ -f "$run/checkpoints/last.ckpt" ] && echo "ckpt_path=$run/checkpoints/last.ckpt"
  return 0
}

# log_sitting LOG CKPT_ARG: a line with the time, the CPU and where the sitting starts from.
log_sitting() {
  local cpu torch_side  # torch's threads (OMP_NUM_THREADS) and the precision conf/trainer/cpu.yaml picks on this CPU
  cpu=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)
  torch_side=$(python -c 'import torch; from motiondiff.runtime.hardware import fast_cpu_precision as p
print(f"{torch.get_num_threads()} torch threads, {p()}")')
  echo "$(date -u +%FT%TZ) sitting starts ($cpu, $(nproc --all) cores, $torch_side, ${2:-from scratch})" >> "$1"
}

# train_sitting EXPERIMENT RUN SITTING LOG [key=value ...]: one sitting of `train.py experiment=EXPERIMENT key=value...`
# in the run folder RUN, resumed from its last.ckpt (or from the committed sitting checkpoint SITTING, "" for none, on
# a machine without the folder), with the sitting's start and end lines in LOG.
train_sitting() {
  local experiment=$1 run=$2 sitting=$3 log=$4 ck; shift 4
  ck=$(resume_arg "$run" "$sitting")
  mkdir -p "$(dirname "$run")"
  log_sitting "$log" "$ck"
  python train.py experiment="$experiment" "$@" hydra.run.dir="$run" $ck
  local code=$?
  echo "$(date -u +%FT%TZ) sitting ends (exit $code)" >> "$log"
  return $code
}

# until_written FILE: wait until FILE has stopped growing (a checkpoint being saved is complete).
until_written() {
  local size=-1
  while [ "$(stat -c %s "$1" 2>/dev/null)" != "$size" ]; do size=$(stat -c %s "$1"); sleep 5; done
}

# until_checkpoint CKPT LOG COMMAND...: run COMMAND in the background until CKPT exists and has stopped growing, then
# kill it (kill -9: a background job ignores SIGINT); returns at once when CKPT is already there.
until_checkpoint() {
  local ckpt=$1 log=$2; shift 2
  [ -f "$ckpt" ] && return 0
  "$@" > "$log" 2>&1 & local pid=$!
  while [ ! -f "$ckpt" ] && kill -0 $pid 2>/dev/null; do sleep 10; done
  until_written "$ckpt"
  pkill -9 -P $pid; kill -9 $pid 2>/dev/null; wait $pid 2>/dev/null
  [ -f "$ckpt" ]
}

# cell_until_step CELL COND STEP WHY: issue 43's ablation cell (ablation_full/cell.sh CELL COND) run until its
# checkpoint at STEP (a 7-digit step number), then stopped and the stop written once into the cell's sittings.log
# with WHY (the study that stopped it); its later sittings go on from that checkpoint.
cell_until_step() {
  local cell=$1 cond=$2 step=$3 why=$4 cells=docs/results/ablation_full/cells
  local steps; steps=$(echo $((10#$step)) | sed ':a;s/\B[0-9]\{3\}\>/,&/;ta')  # 0002000 -> 2,000
  until_checkpoint outputs/ablation_full/${cond}_$cell/checkpoints/step$step.ckpt outputs/${cond}_${cell}_to_$step.log \
    docs/results/ablation_full/cell.sh "$cell" "$cond" || return 1
  grep -q "stopped after its step-$steps" $cells/${cond}_$cell/sittings.log || \
    echo "$(date -u +%FT%TZ) sitting stopped after its step-$steps checkpoint ($why)" >> $cells/${cond}_$cell/sittings.log
}

# copy_cell_curves RUN CELLDIR: each sitting's CSV log of RUN into CELLDIR, named by the steps it holds (a longer copy
# of the same sitting replaces a shorter one).
copy_cell_curves() {
  local run=$1 celldir=$2 f first last
  for f in $run/csv/version_*/metrics.csv; do
    [ -f "$f" ] || continue
    read -r first last < <(awk -F, 'NR==1{for(i=1;i<=NF;i++) if($i=="step") c=i; next} $c!=""{if(min==""||$c<min)min=$c; if($c>max)max=$c} END{print min+0, max+0}' "$f")
    rm -f $celldir/curve_steps_${first}-*.csv; cp "$f" $celldir/curve_steps_${first}-${last}.csv
  done
}
