# motiondiff: `make train` and `make test` set everything up on a fresh machine (see README).
SHELL := /bin/bash
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
SHARED ?= ../shared
BANDAI := $(SHARED)/data/bandai-namco
# Tool caches stay inside the project, never in the user's home.
export WANDB_MODE ?= offline
export MPLCONFIGDIR := $(CURDIR)/.cache/matplotlib
export HF_HOME := $(CURDIR)/.cache/huggingface
export HF_HUB_OFFLINE := 1
export TRANSFORMERS_OFFLINE := 1

.PHONY: setup train test bench lint format data data-full lock clean guided-compare notebooks dashboard

# Training and the benchmark run with tcmalloc where it is installed (`make allocator` installs Debian's as root):
# glibc returns every freed tensor above 32 MB to the kernel and page-faults it back in on the next step, which made
# a CPU-size training step 1.2-1.4x slower (bench/results). Empty where there is none: plain python.
WITH_TCMALLOC = $$(lib=$$(ls /usr/lib/*/libtcmalloc_minimal.so.4 2>/dev/null | head -1); [ -n "$$lib" ] && echo "env LD_PRELOAD=$$lib")

setup: $(VENV)/.installed

# Reinstall when the dependencies change. torch==2.13.0 is the CPU build (a wheel on this machine's disk).
$(VENV)/.installed: pyproject.toml requirements.lock
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet --progress-bar off -c requirements.lock -e '.[dev]'
	@touch $@

# Train the default model on the embedded data, sample a few prompts, and check it does what they say.
PROMPTS := [a person walks forward, a person raises both hands, a person runs, a person bows]
train: setup allocator
	$(WITH_TCMALLOC) $(PY) train.py experiment=cpu_quickstart
	$(PY) sample.py "prompts=$(PROMPTS)" num_samples=2 length=4 export=mp4
	$(PY) -m motiondiff.studies.behaviour num_samples=10
	@echo "checkpoint: $$(ls -t outputs/train/*/checkpoints/last.ckpt | head -1)"
	@echo "samples:    $$(ls -td outputs/sample/*/ | head -1)"

# Two workers, each taking whole test files (module fixtures run once): the suite's subprocesses and imports are
# mostly single-threaded, so the second core does real work.
test: setup browser
	$(PY) -m pytest -q -n 2 --dist loadfile

# Debian packages some targets want: $(call debian_package,<check that it is there>,<package>,<what for>,<else>)
# installs <package> when the check fails and apt-get can run (as root); otherwise it says so in one line and goes on.
define debian_package
	@if $(1); then :; \
	elif [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
		echo "installing Debian's $(2) $(3)"; \
		( export DEBIAN_FRONTEND=noninteractive; apt-get install -y -qq $(2) >/dev/null 2>&1 || \
		  { apt-get update -qq && apt-get install -y -qq $(2) >/dev/null; } ) || \
			echo "note: could not install $(2); $(4)"; \
	else echo "note: no $(2) and no root apt-get; $(4)"; fi
endef

# The HTML viewer's and the dashboard's end-to-end tests screenshot them in headless Chromium, and the web demo's
# test drives the page with Selenium through chromedriver (each test skips with the reason without them).
.PHONY: browser
browser:
	$(call debian_package,command -v chromium >/dev/null 2>&1 || command -v chromium-browser >/dev/null 2>&1 || \
		command -v google-chrome >/dev/null 2>&1,chromium,for the browser tests,the browser screenshot tests will skip)
	$(call debian_package,command -v chromedriver >/dev/null 2>&1,chromium-driver,for the web demo test,the web demo browser test will skip)

# tcmalloc for training (above).
.PHONY: allocator
allocator:
	$(call debian_package,ls /usr/lib/*/libtcmalloc_minimal.so.4 >/dev/null 2>&1,libtcmalloc-minimal4,(faster CPU training),training runs with glibc's allocator (slower))

# Run the notebooks and keep their outputs (figures, the quick start's GIF), so a reader on a code host sees them.
notebooks: setup
	$(PY) notebooks/execute.py notebooks/*.ipynb

# Time training, the forward pass, sampling and text encoding on this machine (<= 10 min on 2 cores); writes
# bench/results/latest.{json,md}. Run it on an otherwise idle machine: other work skews every row.
# `make bench OFFICIAL=<local clone of github.com/GuyTevet/motion-diffusion-model>` adds the official code's column to
# the side-by-side table, timed in the same run.
OFFICIAL ?=
bench: setup allocator
	$(WITH_TCMALLOC) $(PY) bench/run.py $(if $(OFFICIAL),--official "$(OFFICIAL)")

# GuidedMotion against MDM on the complex-motion split (docs/results/guidedmotion), every stage timed in its run.json:
# the three motion VAEs and the latent stage with the CPU recipe, every train clip also mirrored (resumable, in
# sittings: docs/results/guidedmotion/mirror_release/run.sh), then MDM on the same mirrored data for the same total
# wall time, then the comparison, the Tab. 4 ablation and sampling times. A finished stage is not run again.
GC ?= outputs/guided_mirror
GC_REPLICATIONS ?= 5
GC_OUT ?= docs/results/guidedmotion/comparison_mirror
COMP := dataset=bandai_mini_compositional dataset.datamodule.mirror=true
guided-compare: setup allocator
	GC=$(GC) docs/results/guidedmotion/mirror_release/run.sh
	$(PY) -c "import json,sys; sys.exit(0 if 'train_steps' in json.load(open('$(GC)/mdm/run.json')) else 1)" 2>/dev/null || \
	$(WITH_TCMALLOC) $(PY) train.py $(COMP) trainer.max_steps=-1 hydra.run.dir=$(GC)/mdm \
		"+trainer.max_time={seconds: $$($(PY) -c 'import json,sys; print(int(sum((lambda r: r.get("wall_seconds_all_sittings", r["train_seconds"]))(json.load(open(f"$(GC)/{s}/run.json"))) for s in sys.argv[1:])))' vae_motion vae_action vae_specific latent)}" \
		$$(test -f $(GC)/mdm/checkpoints/last.ckpt && echo ckpt_path=$(GC)/mdm/checkpoints/last.ckpt)
	mdm=$$($(PY) -c 'import glob,sys; from motiondiff.runtime.best_checkpoints import best_of; print(best_of(sorted(glob.glob(sys.argv[1])), "val/fid") or "")' "$(GC)/mdm/checkpoints/best-fid-*.ckpt"); \
	$(PY) -m motiondiff.studies.guided_compare latent=$(GC)/latent/checkpoints/last.ckpt \
		mdm=$${mdm:-$(GC)/mdm/checkpoints/last.ckpt} replications=$(GC_REPLICATIONS) out=$(GC_OUT)

# TensorBoard on a training run: RUN=<run folder>, default the newest outputs/train/* trained with logger=tensorboard;
# PORT=<port> if 6006 is taken. A W&B run has its own offline viewer in the terminal: wandb leet <run>/wandb
RUN ?= $(shell ls -d outputs/train/*/tensorboard 2>/dev/null | sort | tail -1 | xargs -r dirname)
PORT ?= 6006
dashboard: setup
	@test -n "$(RUN)" || { echo "error: no run in outputs/train has TensorBoard events: train with logger=tensorboard, \
	or give RUN=<run folder> (a W&B run: $(VENV)/bin/wandb leet <run>/wandb)"; exit 2; }
	@find "$(RUN)" -name 'events.out.tfevents.*' 2>/dev/null | grep -q . || { echo "error: no TensorBoard events in \
	$(RUN): train with logger=tensorboard (a W&B run: $(VENV)/bin/wandb leet $(RUN:/=)/wandb)"; exit 2; }
	@echo "TensorBoard on $(RUN:/=): http://localhost:$(PORT)/ (Ctrl-C stops it)"
	@$(VENV)/bin/tensorboard --logdir "$(RUN)" --port $(PORT)

lint: setup
	$(VENV)/bin/ruff check src tests bench
	$(VENV)/bin/ruff format --check src tests bench

format: setup
	$(VENV)/bin/ruff format src tests bench
	$(VENV)/bin/ruff check --fix src tests bench

# Rebuild the embedded dataset from the Bandai Namco zips (every content x style, two clips each where there are two, <= 4 s),
# with the caption and split rules it was committed with (3 captions per clip, rare actions split like the rest).
data: setup
	$(PY) -m motiondiff.data.preparing.prepare bandai --src $(BANDAI)/bandai-ds1.zip --src $(BANDAI)/bandai-ds2.zip \
		--out data/bandai_mini --per-group 2 --max-frames 80 --compact --seed 0 --caption-variants 0 --rare-to-train 0 --force

# The full Bandai Namco set (2,787 clips, ~450 MB, about 2 minutes) for dataset=bandai and experiment=bandai_text.
# No generated caption repeats a description of the human-style sets (the held-out ones and the one for choosing).
HUMAN_SETS := bandai_human bandai_human_2 bandai_human_val
data-full: setup
	@test -f data/bandai/meta.json && echo "data/bandai is prepared (rm -r data/bandai to rebuild)" || \
	$(PY) -m motiondiff.data.preparing.prepare bandai --src $(BANDAI)/bandai-ds1.zip --src $(BANDAI)/bandai-ds2.zip \
		--out data/bandai --seed 0 $(foreach s,$(HUMAN_SETS),--held-out data/paraphrases/$(s).json)

lock: setup
	( echo "# Exact versions of every installed package (pip freeze of a working .venv); used as pip constraints by the Makefile."; \
	  echo "# Regenerate after changing dependencies in pyproject.toml: make lock"; \
	  $(PY) -m pip freeze --exclude-editable | sed 's/^torch==\(.*\)+cpu/torch==\1/' ) > requirements.lock

clean:
	rm -rf $(VENV) .cache .pytest_cache .ruff_cache
