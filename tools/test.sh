#!/usr/bin/env bash
# README command 2: set up if needed, then run the whole test suite (linters included).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/tools/setup.sh"
source "$root/tools/ros_env.sh"
cd "$root"
exec "$root/.venv/bin/python" -m pytest -q -p no:cacheprovider --durations=15 "$@"
