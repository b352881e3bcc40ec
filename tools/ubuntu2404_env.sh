#!/usr/bin/env bash
# Create or update .venv-noble: the Python library versions of a stock Ubuntu 24.04 (noble)
# ROS 2 Jazzy install, for test/e2e/test_ubuntu2404.py. Idempotent; re-installs only when this
# script or setup.py changed (stamp file, as setup.sh).
#   numpy 1.26.4, scipy 1.11.4, scikit-learn 1.4.1.post1, joblib 1.3.2, PyYAML 6.0.1 (the apt
#   python3-* versions), rclpy + common_interfaces from the ros-jazzy PyPI wheels (as setup.sh's
#   `ros` extra), NO rosbags, matplotlib or tqdm; contact_detector installed with --no-deps.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
venv="${CONTACT_DETECTOR_NOBLE_VENV:-$root/.venv-noble}"
python="${PYTHON:-python3}"
NOBLE_PINS=(numpy==1.26.4 scipy==1.11.4 scikit-learn==1.4.1.post1 joblib==1.3.2 PyYAML==6.0.1)
ROS_WHEELS=('ros-jazzy-rclpy[fastrtps]>=7.1,<8' 'ros-jazzy-common-interfaces>=5.3,<6')

if [ ! -x "$venv/bin/python" ]; then
  echo "ubuntu2404_env: creating $venv"
  "$python" -m venv "$venv"
fi
stamp="$venv/.contact_detector-noble-installed"
want="$(cat "$root/setup.py" "$root/tools/ubuntu2404_env.sh" | sha256sum | cut -d' ' -f1)"
if [ ! -f "$stamp" ] || [ "$(cat "$stamp")" != "$want" ]; then
  echo "ubuntu2404_env: installing Ubuntu 24.04's versions into $venv"
  constraints="$(mktemp)"
  trap 'rm -f "$constraints"' EXIT
  printf '%s\n' "${NOBLE_PINS[@]}" > "$constraints"
  "$venv/bin/python" -m pip install --quiet -c "$constraints" "${NOBLE_PINS[@]}" \
    "${ROS_WHEELS[@]}" 2>&1 | grep -vE "is ignored: it is neither|BuildBackendWarning|warnings.warn" || true
  "$venv/bin/python" -m pip install --quiet --no-deps -e "$root" 2>&1 \
    | grep -vE "is ignored: it is neither|BuildBackendWarning|warnings.warn" || true
  # The set must be exactly noble's: fail loudly if a wheel dragged another version in.
  "$venv/bin/python" - "${NOBLE_PINS[@]}" <<'PY'
import importlib.metadata as md
import importlib.util
import sys
for pin in sys.argv[1:]:
    name, version = pin.split('==')
    got = md.version(name)
    if got != version:
        sys.exit(f'ubuntu2404_env: {name} is {got}, expected {version}')
for absent in ('rosbags', 'matplotlib', 'tqdm'):
    if importlib.util.find_spec(absent) is not None:
        sys.exit(f'ubuntu2404_env: {absent} is installed but must not be')
import contact_detector, rclpy  # noqa: E401,F401
PY
  echo "$want" > "$stamp"
fi
