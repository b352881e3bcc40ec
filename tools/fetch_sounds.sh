#!/usr/bin/env bash
# Fetch the real recorded sounds of the simulator's 'real_sounds' family into the cache
# ($CONTACT_DETECTOR_SOUNDS or ~/.cache/contact_detector/sounds). Idempotent; see
# contact_detector/sim/sound_bank.py and docs/simulator.md. Needs apt-get + dpkg-deb.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
venv="${CONTACT_DETECTOR_VENV:-$root/.venv}"
exec "$venv/bin/python" -c 'import sys; from contact_detector.sim.sound_bank import main; sys.exit(main(sys.argv[1:]))' "$@"
