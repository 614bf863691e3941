# Sourced by the scripts that train in sittings (final_run.sh, bandai_action/long_run/run.sh, ablation_full/cell.sh,
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
