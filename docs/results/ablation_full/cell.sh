#!/bin/bash
# One cell of issue 43's full-Bandai ablation (rules: docs/results/ablation_plan.md), resumed across sittings.
#   docs/results/ablation_full/cell.sh <cell of conf/ablation> [text|action|none]
# text cells are MDM's (loss=simple); action and none are vvMDM's Tab. 1 (loss=geometric, as vvMDM trains).
# A sitting resumes from the run folder, else from the sitting checkpoint committed in sittings/. A cell is finished
# when its last checkpoint is at the cap or the stopping rule fired; then its best-val-FID checkpoint is evaluated
# once on the test split (20 replications) into cells/<cond>_<cell>/test/. Stop a sitting with kill -9 <python pid>
# (a background job ignores SIGINT): the checkpoint after the latest evaluation, at most 1,000 steps back, is where
# the next sitting starts. An ε cell is also tested with eps_fix's S3 sampling (MDM's DDIM steps and the static x̂0
# clip), beside its own (MDM's DDIM steps), for issue 43 point 2's account (docs/results/eps_fix/rules.md).
# Edit this file only by writing a copy and moving it over (a running bash reads its script as it goes).
set -u
cd "$(dirname "$0")/../../.."; source .venv/bin/activate; source docs/results/sittings.sh; use_tcmalloc
CELL=$1; COND=${2:-text}
case $COND in
  text) EXTRA="";;
  action) EXTRA="condition=action loss=geometric";;
  none) EXTRA="condition=none loss=geometric";;
  *) echo "condition must be text, action or none, got $COND"; exit 2;;
esac
# The ε cells train with the geometric terms times abar_t and sample with MDM's DDIM steps (never t = 999):
# docs/results/eps_fix/rules.md, amendment 2 (2026-12-07); the x0 and v cells keep MDM's unweighted terms, uniform steps
[[ $CELL == eps_* ]] && EXTRA="$EXTRA loss.time_weighting=alpha_bar diffusion.timestep_spacing=leading"
NAME=${COND}_${CELL}; HERE=docs/results/ablation_full
RUN=outputs/ablation_full/$NAME; SITTING=$HERE/sittings/$NAME.ckpt; CELLDIR=$HERE/cells/$NAME
finished() {  # the cap reached, or the plateau rule fired at the last evaluation (both read from the preset)
  python - "$RUN/checkpoints/last.ckpt" <<'PY'
import sys, torch
from hydra import compose, initialize_config_dir
from motiondiff.cli.common import REPO_DIR, register_resolvers
from motiondiff.eval.plateau import plateaued
try:
    c = torch.load(sys.argv[1], map_location="cpu", weights_only=False)
except FileNotFoundError:
    sys.exit(1)
register_resolvers()
with initialize_config_dir(config_dir=str(REPO_DIR / "conf"), version_base="1.3"):
    cfg = compose("train", overrides=["experiment=ablation_full"])
rule = cfg.callbacks.plateau
h = [tuple(x) for x in c["callbacks"].get("PlateauStop", {}).get("history", [])]
capped = c["global_step"] >= cfg.trainer.max_steps
sys.exit(0 if capped or plateaued(h, rule.min_gain, rule.window, rule.start, rule.mode) else 1)
PY
}
copy_curves() { copy_cell_curves $RUN $CELLDIR; }  # each sitting's CSV log beside sittings.log (sittings.sh)
ck=$(resume_arg $RUN $SITTING)
mkdir -p $CELLDIR
if ! finished; then
  log_sitting $CELLDIR/sittings.log "$ck"
  python train.py experiment=ablation_full ablation=$CELL $EXTRA hydra.run.dir=$RUN $ck
  echo "$(date -u +%FT%TZ) sitting ends (exit $?)" >> $CELLDIR/sittings.log
  copy_curves
fi
finished || exit 0
if [ ! -f $CELLDIR/test/metrics.json ]; then
  best=$(python $HERE/best_checkpoint.py $NAME) || exit 1  # the lowest logged val FID's (a resumed run can keep stale ones)
  # action_accuracy=false: a text cell's label-caption pass (issue 39's extra metric, not an ablation column) would
  # double the generation; it runs after each replication's own motions, so the reported numbers are the same
  python evaluate.py checkpoint=$best dataset=bandai split=test replications=20 mm_replications=0 wandb=false \
    action_accuracy=false hydra.run.dir=$CELLDIR/test
fi
if [[ $CELL == eps_* ]] && [ ! -f $CELLDIR/test_leading_static/metrics.json ]; then  # point 2's account: S3 of eps_fix
  best=$(python $HERE/best_checkpoint.py $NAME) || exit 1
  python evaluate.py checkpoint=$best dataset=bandai split=test replications=20 mm_replications=0 wandb=false \
    action_accuracy=false timestep_spacing=leading clip_x0=static hydra.run.dir=$CELLDIR/test_leading_static
fi
copy_curves
