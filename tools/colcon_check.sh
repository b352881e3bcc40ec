#!/usr/bin/env bash
# colcon build and colcon test of this package, as on a ROS 2 Jazzy install, with colcon and
# ament_package from PyPI (setup.py extra "colcon", installed by tools/setup.sh).
#
#   tools/colcon_check.sh [WORKSPACE]     default: a new temporary folder, removed at the end
#
# Copies the package's files (git's tracked and untracked-not-ignored ones) into
# WORKSPACE/src/contact_detector, runs `colcon build`, checks what it installed (launch file,
# params files, both node executables, the ament index entry), sources install/setup.bash
# and runs `colcon test` with COLCON_PYTEST_ARGS (default: the tests that do not start
# rclpy or run colcon, linters included), then `colcon test-result --verbose`. Exit status: non-zero if a
# step or a test failed.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
venv="${CONTACT_DETECTOR_VENV:-$root/.venv}"
"$root/tools/setup.sh"
source "$root/tools/ros_env.sh"
export PATH="$venv/bin:$PATH"
pytest_args="${COLCON_PYTEST_ARGS:--m 'not rclpy and not colcon' -q -p no:cacheprovider}"

if [ $# -ge 1 ]; then
  ws="$1"
  mkdir -p "$ws"
else
  ws="$(mktemp -d -t contact_detector_ws.XXXXXX)"
  trap 'rm -rf "$ws"' EXIT
fi
ws="$(cd "$ws" && pwd)"
pkg="$ws/src/contact_detector"
rm -rf "$pkg"
mkdir -p "$pkg"
(cd "$root" && git ls-files -z --cached --others --exclude-standard \
  | tar --null --ignore-failed-read -T - -cf - 2>/dev/null) | tar -xf - -C "$pkg"

cd "$ws"
echo "colcon_check: colcon build in $ws"
colcon build --packages-select contact_detector --event-handlers console_cohesion-
share="$ws/install/contact_detector/share/contact_detector"
for file in "$share/launch/contact_detector.launch.py" "$share/params/contact_detector.yaml" \
    "$share/params/hsr.yaml" "$share/package.xml" "$share/LICENSE" "$share/CHANGELOG.rst" \
    "$ws/install/contact_detector/lib/contact_detector/contact_detector_node" \
    "$ws/install/contact_detector/lib/contact_detector/contact_detector_lifecycle_node" \
    "$ws/install/contact_detector/share/ament_index/resource_index/packages/contact_detector"; do
  if [ ! -e "$file" ]; then
    echo "colcon_check: colcon build did not install $file" >&2
    exit 1
  fi
done

# What a user does next: source the workspace; the package is then found by its index.
set +u
source "$ws/install/setup.bash"
set -u
python -c "
from ament_index_python.packages import get_package_prefix, get_package_share_directory
import contact_detector
assert get_package_share_directory('contact_detector') == '$share'
assert contact_detector.__file__.startswith('$ws/install/'), contact_detector.__file__
print('colcon_check: sourced install/setup.bash: contact_detector from', get_package_prefix('contact_detector'))
"

echo "colcon_check: colcon test --pytest-args $pytest_args"
test_status=0
eval "colcon test --packages-select contact_detector --event-handlers console_direct+ \
  --pytest-args $pytest_args" || test_status=$?
colcon test-result --verbose || test_status=$?
exit "$test_status"
