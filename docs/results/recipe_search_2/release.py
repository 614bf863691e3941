"""Release rule F's winner after it met shipping rule S (docs/results/recipe_search_2/rules.md) as
checkpoints/models/bandai_text_ft_101k: the EMA weights of the step-4,000 checkpoint of proxy F0 (97,000 steps of
the first recipe, then 4,000 of this one), with its provenance. Run on the machine that trained it.

    python docs/results/recipe_search_2/release.py
"""

from motiondiff.model_files.release import cpu_description, release_checkpoint
from motiondiff.runtime.hardware import fast_cpu_precision

weights, config = release_checkpoint(
    "outputs/recipe_search_2/F0/checkpoints/step0004000.ckpt",
    "checkpoints/models/bandai_text_ft_101k",
    data="data/bandai (make data-full): all Bandai Namco train clips and their left-right mirrors; captions generated "
    "from labels and measured motion, none human-written",
    recipe="the first recipe (experiment=bandai_text_long, docs/results/recipe_search/rules.md) to its end at step "
    "97,000, then experiment=bandai_text_finetune (docs/results/recipe_search_2/rules.md, proxy F0): 4,000 steps from "
    "those EMA weights with a fresh optimizer and EMA, AdamW 1e-4, 100 warm-up steps, cosine to 0; the same data "
    "settings (mirror, windows 40-120 frames, balance 0.5)",
    training_time="about 599 min for the first recipe's 97,000 steps (its sittings table) and 21 min (1,264 s) for "
    "the fine-tune",
    machine="first recipe: 2-core AMD EPYCs (sitting 1 bf16 on AVX512-BF16, the rest fp32 on AVX2); fine-tune: "
    + cpu_description(),
    precision=fast_cpu_precision(),
)
print(weights, config)
