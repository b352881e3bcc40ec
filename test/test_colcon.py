"""colcon build and colcon test of the package, as on a ROS install (tools/colcon_check.sh).

colcon, colcon-ros and ament_package come from PyPI (setup.py extra "colcon"). The build is
checked for what it installs; colcon test runs the tests that do not start rclpy (linters
included) from the installed package, and colcon test-result must report no failure.
"""

from pathlib import Path
import re
import shutil
import subprocess
import sys

import pytest

ROOT = Path(__file__).resolve().parents[1]

pytestmark = pytest.mark.colcon


@pytest.mark.skipif(shutil.which('colcon', path=str(Path(sys.executable).parent)) is None,
                    reason='colcon is not installed in this venv (tools/setup.sh installs it)')
def test_colcon_build_and_test(tmp_path):
    done = subprocess.run([str(ROOT / 'tools' / 'colcon_check.sh'), str(tmp_path / 'ws')],
                          cwd=ROOT, capture_output=True, text=True, timeout=1200)
    output = done.stdout + done.stderr
    assert done.returncode == 0, output[-6000:]
    assert 'sourced install/setup.bash: contact_detector from' in output
    summary = re.search(r'Summary: (\d+) tests, (\d+) errors, (\d+) failures', output)
    assert summary, output[-3000:]
    tests, errors, failures = map(int, summary.groups())
    assert tests > 100 and errors == 0 and failures == 0
    results = list((tmp_path / 'ws' / 'build' / 'contact_detector').rglob('pytest.xml'))
    assert results, 'colcon test wrote no JUnit result'
