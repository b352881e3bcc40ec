#!/usr/bin/env bash
# Create or update the project's virtual environment (idempotent). Sourced by demo.sh/test.sh.
# Installs contact_detector (editable) with ROS 2 Jazzy rclpy + common_interfaces from PyPI
# wheels, so no apt ROS is needed. Re-installs only when setup.py or this script changed.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
venv="${CONTACT_DETECTOR_VENV:-$root/.venv}"
python="${PYTHON:-python3}"

if ! command -v "$python" >/dev/null 2>&1; then
  echo "setup: $python not found; install Python >= 3.10 (apt install python3 python3-venv)" >&2
  exit 1
fi
if ! "$python" -c 'import sys; sys.exit(0 if (3, 10) <= sys.version_info[:2] <= (3, 13) else 1)'; then
  echo "setup: Python 3.10-3.13 is needed (the ROS 2 Jazzy wheels), found $("$python" -V)" >&2
  exit 1
fi
if [ ! -x "$venv/bin/python" ]; then
  echo "setup: creating $venv"
  if ! "$python" -m venv "$venv"; then
    echo "setup: python3 -m venv failed; on Debian/Ubuntu run: sudo apt install python3-venv" >&2
    rm -rf "$venv"
    exit 1
  fi
fi
stamp="$venv/.contact_detector-installed"
want="$(cat "$root/setup.py" "$root/tools/setup.sh" | sha256sum | cut -d' ' -f1)"
if [ ! -f "$stamp" ] || [ "$(cat "$stamp")" != "$want" ]; then
  echo "setup: installing contact_detector and its dependencies into $venv"
  # pip's notes about this machine's local index folders are noise here.
  "$venv/bin/python" -m pip install --quiet -e "$root[ros,train,safe,test,colcon]" 2>&1 \
    | grep -vE "is ignored: it is neither|BuildBackendWarning|warnings.warn" || true
  "$venv/bin/python" -c 'import contact_detector, rclpy, rosbags, sklearn, soundfile' || {
    echo "setup: the install failed (see above)" >&2; exit 1; }
  echo "$want" > "$stamp"
fi
# The real recorded sounds of the simulator's 'real_sounds' family (cached, idempotent). A
# failure leaves that family unavailable (its tests skip, except under CI) and nothing else.
if ! CONTACT_DETECTOR_VENV="$venv" "$root/tools/fetch_sounds.sh" >/dev/null; then
  echo "setup: the real sound bank was not fetched; the simulator's 'real_sounds' family" \
    "needs it (run tools/fetch_sounds.sh)" >&2
fi
