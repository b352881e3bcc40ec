#!/usr/bin/env bash
# Rebuild the shipped F/T-only model (robots without a microphone): simulate the training set
# over all twelve condition sets ('wide'), then train with --no-audio: the six spectral F/T
# features and the six vector-shift features, the shipped rule; contact labels from 30 ms after
# the onset (the first instants of a touch look like a knock on the hand to F/T alone). Writes
# models/contact_forest_ft.npz (loads with numpy alone), its card and models/report_ft.
# docs/offline.md "Robots without a microphone" has the figures and the command to check them.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/tools/setup.sh"
cd "$root"
data="${1:-$root/data/train_wide}"
.venv/bin/contact-detector simulate "$data" --trials 240 --seed 11 --conditions wide \
  --overwrite --quiet
.venv/bin/contact-detector train "$data" --no-audio \
  --extra-features force_shift,torque_shift,force_shift_min,torque_shift_min,force_shift_max,torque_shift_max \
  --ft-window 64 --ft-detrend mean --delta-window 1 --label-start 0.03 \
  --threshold 0.95 --sustain-frames 15 --sustain-threshold 0.3 \
  --out models/contact_forest_ft.npz --report models/report_ft --jobs 2 --seed 0
