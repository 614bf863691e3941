#!/bin/bash
# One run of rules.md beside this file on the full Bandai val split (2 replications, DDIM-50, the model's guidance),
# measured exactly as issue 43's ε candidates (docs/results/eps_fix/measure.sh, with the sampler's own spacing).
#   docs/results/geometric_reduction/measure.sh <checkpoint> <name>      writes val/<name>.md and .json here
cd "$(dirname "$0")/../../.."
HERE=docs/results/geometric_reduction exec docs/results/eps_fix/measure.sh "$1" "$2"
