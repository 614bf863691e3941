#!/bin/bash
# Run the README's commands (explicit model files that exist in both trees) in tree $1, outputs under $2.
T=$1; O=$2; mkdir -p $O; cd $T
export PYTHONPATH=$T/src MPLCONFIGDIR=/tmp/eq40mpl WANDB_MODE=offline HF_HUB_OFFLINE=1 TRANSFORMERS_OFFLINE=1
PY=/work/main/.venv/bin/python
TXT=checkpoints/models/bandai_mini_text_cpu.safetensors
ACT=checkpoints/models/bandai_action_cpu.safetensors
$PY sample.py checkpoint=$TXT text="a person walks forward" export=none hydra.run.dir=$O/s1 > $O/s1.log 2>&1; echo s1 $?
$PY sample.py checkpoint=$TXT "prompts=[a person walks forward:4, a person waves both hands:3]" export=none hydra.run.dir=$O/s2 > $O/s2.log 2>&1; echo s2 $?
$PY edit.py checkpoint=$TXT input=test:dataset-1_walk_active_001 kind=parts parts=$3 text="a person raises both hands" export=none hydra.run.dir=$O/e1 > $O/e1.log 2>&1; echo e1 $?
$PY sample.py checkpoint=$ACT action=wave-right-hand export=none hydra.run.dir=$O/s3 > $O/s3.log 2>&1; echo s3 $?
$PY - > $O/api.log 2>&1 <<PYEOF
import numpy as np
from motiondiff.pipelines import MotionPipeline
pipe = MotionPipeline.from_pretrained("$TXT")
out = pipe("a person walks forward", seconds=4, num_samples=2)
edited = pipe.edit_parts(out, "a person raises both hands", parts="upper_body")
np.save("$O/api_out.npy", np.stack(out.joints)); np.save("$O/api_edit.npy", np.stack(edited.joints))
print("ok")
PYEOF
echo api $?
