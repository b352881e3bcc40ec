#!/usr/bin/env bash
# README command 1: set up if needed, then run the main job (the live demo).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/tools/setup.sh"
source "$root/tools/ros_env.sh"
cd "$root"
exec "$root/.venv/bin/contact-detector" demo "$@"
