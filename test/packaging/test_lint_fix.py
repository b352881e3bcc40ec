# Copyright 2026 contact_detector developers
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.

"""
tools/lint_fix.py: what it rewrites, that a second run changes nothing, and the copyright rule.

The ament linters themselves run in test_flake8.py, test_pep257.py and test_copyright.py; this
file checks the fixer and the copyright rule test_copyright.py falls back on.
"""

import ast
import importlib.util
import inspect
from pathlib import Path
import subprocess
import sys

import pytest

ROOT = Path(__file__).resolve().parents[2]
spec = importlib.util.spec_from_file_location('lint_fix', ROOT / 'tools' / 'lint_fix.py')
lint_fix = importlib.util.module_from_spec(spec)
spec.loader.exec_module(lint_fix)

pytestmark = pytest.mark.linter


def fix(text: str, name: str = 'module.py') -> str:
    """Run every step on ``text``; check that a second run changes nothing."""
    problems = []
    fixed = lint_fix.fix_text(text, problems, Path(name))
    assert lint_fix.fix_text(fixed, problems, Path(name)) == fixed
    assert not problems
    return fixed


def body(text: str) -> str:
    """Drop the copyright header the fixer adds to every file."""
    header = lint_fix.header_comment() + '\n\n'
    assert text.startswith(header)
    return text[len(header):]


def test_imports_sorted_google_style_with_the_package_among_third_party():
    source = ('"""Doc."""\n\nimport sys\nimport os\n\nimport numpy as np\nimport rclpy\n\n'
              'from contact_detector.errors import InputError, ConfigError\n\nx = 1\n')
    assert body(fix(source)) == (
        '"""Doc."""\n\nimport os\nimport sys\n\n'
        'from contact_detector.errors import ConfigError, InputError\nimport numpy as np\n'
        'import rclpy\n\nx = 1\n')


def test_imports_separated_by_code_are_not_moved_but_reported():
    source = "import sys\n\nimport numpy\n\nsys.path.insert(0, '.')\n\nimport bench\n"
    problems = []
    assert body(lint_fix.fix_text(source, problems)) == source
    assert problems and 'by hand' in problems[0]


def test_comment_between_imports_moves_with_the_import_below_it():
    source = 'import numpy\n# the node needs rclpy\nimport contact_detector\n'
    assert body(fix(source)) == '# the node needs rclpy\nimport contact_detector\nimport numpy\n'


def test_imports_a_merge_repeated_become_one_statement():
    source = ('import os\nfrom contact_detector.errors import InputError, ConfigError\n'
              'import numpy as np\n\nfrom contact_detector.errors import ModelError, InputError\n'
              'import os\n')
    assert body(fix(source)) == ('import os\n\n'
                                 'from contact_detector.errors import ConfigError, InputError, '
                                 'ModelError\nimport numpy as np\n')


def test_two_imports_from_one_module_binding_different_names_stay_two():
    source = 'from contact_detector.cli import detect\nfrom contact_detector.cli import evaluate\n'
    assert body(fix(source)) == source


def test_long_from_import_is_wrapped_under_the_bracket():
    names = ', '.join(f'name_{i:02d}' for i in range(12)[::-1])
    fixed = body(fix(f'from contact_detector.io.messages import {names}\n'))
    assert all(len(line) <= 99 for line in fixed.splitlines())
    assert ast.dump(ast.parse(fixed)) == ast.dump(ast.parse(
        'from contact_detector.io.messages import '
        + ', '.join(f'name_{i:02d}' for i in range(12))))


def test_multi_line_docstring_summary_moves_to_the_second_line():
    source = ('def f():\n    """Summary.\n\n    More.\n    """\n    return 1\n\n\n'
              'def g():\n    """One line."""\n')
    fixed = body(fix(source))
    assert fixed.startswith('def f():\n    """\n    Summary.\n\n    More.\n    """\n')
    assert '"""One line."""' in fixed
    namespace = {}
    exec(fixed, namespace)
    assert inspect.getdoc(namespace['f']) == 'Summary.\n\nMore.'


def test_dict_calls_become_literals_and_visual_indent_follows_the_bracket():
    source = ('x = dict(a=1, b=[2])\ny = list()\nz = tuple()\n'
              'w = dict(alpha=1,\n         beta=2)\n')
    fixed = body(fix(source))
    assert fixed == ("x = {'a': 1, 'b': [2]}\ny = []\nz = ()\n"
                     "w = {'alpha': 1,\n     'beta': 2}\n")


def test_dict_call_kept_where_dict_is_rebound_or_the_line_would_be_too_long():
    shadowed = 'dict = MyDict\nx = dict(a=1)\n'
    assert body(fix(shadowed)) == shadowed
    n = max(n for n in range(1, 30)
            if len('x = dict(' + ', '.join(f'k{i}={i}' for i in range(n)) + ')') <= 99)
    long_line = 'x = dict(' + ', '.join(f'k{i}={i}' for i in range(n)) + ')\n'
    assert body(fix(long_line)) == long_line


def test_quotes_follow_flake8_quotes_defaults_where_the_text_stays_the_same():
    source = r"""a = "plain"
b = "it's"
c = "back\\slash"
d = '''
line
'''
e = f'''{a!r}
'''
g = '''ends with "'''
"""
    expected = (source.replace('a = "plain"', "a = 'plain'")
                .replace("d = '''\nline\n'''", 'd = """\nline\n"""')
                .replace("e = f'''{a!r}\n'''", 'e = f"""{a!r}\n"""'))
    assert expected.count('"""') == 4
    fixed = body(fix(source))
    assert fixed == expected
    before, after = {}, {}
    exec(source, before)
    exec(fixed, after)
    assert [before[k] for k in 'abcdeg'] == [after[k] for k in 'abcdeg']


def test_header_goes_after_a_shebang_and_is_not_added_twice():
    fixed = fix('#!/usr/bin/env python3\n"""Doc."""\n')
    assert fixed.startswith('#!/usr/bin/env python3\n\n# Copyright 2026 contact_detector')
    assert lint_fix.copyright_problem(fixed) is None


def test_stdlib_named_package_gets_a_noqa_line_above_the_header():
    fixed = fix('"""Input/output."""\n', name='pkg/io/__init__.py')
    assert fixed.startswith('# noqa: A005')
    assert lint_fix.copyright_problem(fixed) is None


@pytest.mark.parametrize('text, expected', [
    ('"""No header."""\n', 'could not find copyright notice'),
    ('# Copyright 2026 someone\n#\n# Permission is hereby granted, free of charge (MIT)\n',
     'license=<unknown>'),
    (lint_fix.header_comment().replace('limitations under', 'restrictions under') + '\n',
     'license=<unknown>'),
])
def test_copyright_rule_reports_what_ament_copyright_reports(text, expected):
    assert expected in lint_fix.copyright_problem(text)


def test_copyright_report_needs_license_and_contributing_at_a_repository_root(tmp_path):
    (tmp_path / '.git').mkdir()
    (tmp_path / 'package.xml').write_text('<package/>')
    (tmp_path / 'setup.py').write_text('"""Not checked: setup.py beside package.xml."""\n')
    (tmp_path / 'a.py').write_text(lint_fix.header_comment() + '\n')
    errors = lint_fix.copyright_report([tmp_path])
    assert sorted(Path(e.split(':')[0]).name for e in errors) == ['CONTRIBUTING.md', 'LICENSE']
    (tmp_path / 'LICENSE').write_text((ROOT / 'LICENSE').read_text())
    (tmp_path / 'CONTRIBUTING.md').write_text(lint_fix.APACHE2_CONTRIBUTING)
    assert lint_fix.copyright_report([tmp_path]) == []
    (tmp_path / 'LICENSE').write_text((ROOT / 'LICENSE').read_text().replace('patent', 'pat'))
    assert [Path(e.split(':')[0]).name for e in lint_fix.copyright_report([tmp_path])] == [
        'LICENSE']


@pytest.mark.slow
def test_the_package_is_a_fixed_point_of_the_fixer():
    result = subprocess.run([sys.executable, str(ROOT / 'tools' / 'lint_fix.py'), '--check'],
                            capture_output=True, text=True, cwd=ROOT)
    assert result.returncode == 0, result.stdout + result.stderr
