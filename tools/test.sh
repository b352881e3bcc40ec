#!/usr/bin/env bash
# README command 2: set up if needed, then run the whole test suite (linters included).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/tools/setup.sh"
# Ubuntu 24.04's library versions, for test/e2e/test_ubuntu2404.py (cached by a stamp file).
"$root/tools/ubuntu2404_env.sh"
source "$root/tools/ros_env.sh"
cd "$root"
exec "$root/.venv/bin/python" -m pytest -q -p no:cacheprovider --durations=15 "$@"
