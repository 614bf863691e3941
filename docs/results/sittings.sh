# Sourced by the scripts that train in sittings (final_run.sh, bandai_action/long_run/run.sh, ablation_full/cell.sh,
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
  echo "$(date -u +%FT%TZ) sitting starts ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), ${2:-from scratch})" >> "$1"
}

# until_checkpoint CKPT LOG COMMAND...: run COMMAND in the background until CKPT exists and has stopped growing, then
# kill it (kill -9: a background job ignores SIGINT); returns at once when CKPT is already there.
until_checkpoint() {
  local ckpt=$1 log=$2; shift 2
  [ -f "$ckpt" ] && return 0
  "$@" > "$log" 2>&1 & local pid=$!
  while [ ! -f "$ckpt" ] && kill -0 $pid 2>/dev/null; do sleep 10; done
  local size=-1; while [ "$(stat -c %s "$ckpt" 2>/dev/null)" != "$size" ]; do size=$(stat -c %s "$ckpt"); sleep 5; done
  pkill -9 -P $pid; kill -9 $pid 2>/dev/null; wait $pid 2>/dev/null
  [ -f "$ckpt" ]
}
