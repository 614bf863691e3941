#!/bin/bash
cd /work/main; source .venv/bin/activate
python evaluate.py checkpoint=shipped dataset=bandai split=val replications=5 mm_replications=0 wandb=false hydra.run.dir=outputs/evaluate/speed_ddim50_r5 > /tmp/speed_ddim.log 2>&1
python evaluate.py checkpoint=shipped dataset=bandai split=val replications=20 mm_replications=0 sampler=dpmpp steps=10 wandb=false hydra.run.dir=outputs/evaluate/speed_dpmpp10_r20 > /tmp/speed_dpmpp.log 2>&1
