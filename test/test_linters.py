"""ament-style linters: flake8 (ament's settings, single quotes) and pep257 (numpy style)."""

from pathlib import Path
import subprocess
import sys

import pytest

ROOT = Path(__file__).resolve().parents[1]
TARGETS = ['contact_detector', 'test', 'benchmarks', 'setup.py']


@pytest.mark.linter
def test_flake8():
    result = subprocess.run([sys.executable, '-m', 'flake8', *TARGETS], cwd=ROOT,
                            capture_output=True, text=True)
    assert result.returncode == 0, f'flake8 found problems:\n{result.stdout}{result.stderr}'


@pytest.mark.linter
def test_pep257():
    # ament_pep257's defaults: numpy conventions, D100-D107 (missing docstrings) not required.
    result = subprocess.run([sys.executable, '-m', 'pydocstyle', 'contact_detector'],
                            cwd=ROOT, capture_output=True, text=True)
    assert result.returncode == 0, f'pydocstyle found problems:\n{result.stdout}'
