#!/usr/bin/env bash
# README command 2: set up if needed, then run the whole test suite (linters included).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/tools/setup.sh"
# Ubuntu 24.04's library versions, for test/e2e/test_ubuntu2404.py (cached by a stamp file).
"$root/tools/ubuntu2404_env.sh"
source "$root/tools/ros_env.sh"
cd "$root"
# Two workers (pytest-xdist), one per core of the 2-core CI machine, each test file on one worker
# (its module fixtures built once); test/conftest.py gives each worker a DDS domain of its own.
# A later `-n 0` on the command line runs the tests in one process.
exec "$root/.venv/bin/python" -m pytest -q -p no:cacheprovider --durations=15 -n 2 \
  --dist loadfile "$@"
