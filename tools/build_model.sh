#!/usr/bin/env bash
# Rebuild the shipped model: simulate the training set (40 trials of each of the twelve
# simulator families), then train with the defaults chosen by leave-one-family-out
# (docs/generalisation.md). Writes models/contact_forest.npz (loads with numpy alone), its
# card and report.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/tools/setup.sh"
cd "$root"
data="${1:-$root/data/train}"
.venv/bin/contact-detector simulate "$data" --trials 480 --seed 11 --conditions wide \
  --overwrite --quiet
.venv/bin/contact-detector train "$data" --out models/contact_forest.npz \
  --report models/report --jobs 2 --seed 0
