#!/usr/bin/env python3
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
Fix the mechanical findings of ament_flake8, ament_pep257 and ament_copyright in place.

    .venv/bin/python tools/lint_fix.py            # fix every Python file of this package
    .venv/bin/python tools/lint_fix.py --check    # list what would change, exit 1 if anything
    .venv/bin/python tools/lint_fix.py FILE...    # only these files

Idempotent (a second run changes nothing) and behaviour-preserving: after each step the file's
syntax tree is compared with the one before, normalised for exactly what the step may change
(docstring layout, the names a block of imports binds, ``dict()`` -> ``{}``; the string
steps must leave the tree identical); a step whose result differs in anything else is dropped
and reported. Exit status 1 if something is left for a hand fix (or, with --check, if a file
would change). The steps:

1. C408: ``dict()``, ``dict(a=x)``, ``list()``, ``tuple()`` become ``{}``, ``{'a': x}``,
   ``[]``, ``()`` (not when a line would pass 99 characters, nor when the module rebinds the
   name).
2. I100/I101/I201 (flake8-import-order, google style, no application names, as
   ament_flake8's configuration sets it): each block of consecutive top-level imports that
   is out of order is sorted, names inside ``from x import a, b`` are sorted, and one blank
   line separates the groups (standard library, then third party, which includes
   ``contact_detector`` itself). Comment lines between imports move with the import below
   them; a name imported twice in one block (as a merge can leave it) is imported once.
   Imports separated by code (a ``sys.path`` insert) are not moved across it: the order
   problems left there are printed for a hand fix.
3. D213 (ament_pep257): a multi-line docstring's summary moves to the line after the
   opening quotes.
4. ament_copyright: a file without a copyright notice gets ``Copyright <YEAR>
   contact_detector developers`` and the Apache-2.0 notice as a comment block, after any
   shebang or coding line, exactly as ``ament_copyright --add-missing`` writes it.
5. Q000/Q001/Q002 (flake8-quotes' defaults): one-line strings in single quotes, triple-quoted
   ones in double quotes, where the string's text stays the same (no quote of the new kind,
   no backslash inside).
6. A005 (flake8-builtins): a module named like a standard library module (the subpackage
   ``contact_detector.io``) gets a ``# noqa: A005`` first line.

What it cannot fix (D401 imperative mood, D417, lines too long, ...) the linters still report:
run ``.venv/bin/python -m pytest test/test_flake8.py test/test_pep257.py test/test_copyright.py``.
"""

import argparse
import ast
import hashlib
import io
import os
from pathlib import Path
import re
import sys
import tokenize

ROOT = Path(__file__).resolve().parents[1]
MAX_LINE = 99
YEAR = 2026
HOLDER = 'contact_detector developers'
# ament_copyright's apache2 file header template (template/apache2_header.txt).
APACHE2_HEADER = """{copyright}

Licensed under the Apache License, Version 2.0 (the "License");
you may not use this file except in compliance with the License.
You may obtain a copy of the License at

    http://www.apache.org/licenses/LICENSE-2.0

Unless required by applicable law or agreed to in writing, software
distributed under the License is distributed on an "AS IS" BASIS,
WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
See the License for the specific language governing permissions and
limitations under the License."""
# Directories never walked: ament's linters skip names starting with '.' or '_'; colcon's
# output folders are not sources.
SKIP_DIRS = {'build', 'install', 'log'}


class StepRejected(Exception):
    """A step's result changed more than the step is allowed to change."""


# --------------------------------------------------------------------------------------------
# Files


def python_files(root: Path) -> list[Path]:
    """
    List the Python files the ament linters check when run from the package root ``root``.

    Directories starting with ``.`` or ``_``, holding an ``AMENT_IGNORE`` file, or named
    build/install/log are skipped.
    """
    found = []
    for dirpath, dirnames, filenames in os.walk(root):
        if 'AMENT_IGNORE' in dirnames + filenames:
            dirnames[:] = []
            continue
        dirnames[:] = sorted(d for d in dirnames
                             if d[0] not in '._' and not (Path(dirpath) == root
                                                          and d in SKIP_DIRS))
        found.extend(Path(dirpath) / name for name in sorted(filenames) if name.endswith('.py'))
    return found


# --------------------------------------------------------------------------------------------
# ament_copyright's rule (a port of ament_copyright.parser for '#' comments)


def _next_line(content: str, index: int) -> int:
    found = [i for i in (content.find('\n', index), content.find('\r', index)) if i != -1]
    if not found:
        return len(content)
    index = min(found)
    return index + 2 if content[index:index + 2] == '\r\n' else index + 1


def _is_comment(content: str, index: int) -> bool:
    return content[index:index + 1] == '#' or content[index:index + 2] == '//'


def _past_shebang_and_coding(content: str) -> int:
    index = 0
    while index < len(content) and _is_comment(content, index):
        line = content[index:_next_line(content, index)]
        if not (line.startswith('#!') or 'coding=' in line or 'coding:' in line):
            break
        index = _next_line(content, index)
    return index


def _past_empty_lines(content: str, index: int) -> int:
    while index < len(content) and _next_line(content, index) == index + 1:
        index = _next_line(content, index)
    return index


def _comment_block(content: str, index: int) -> str | None:
    match = re.compile('^(#|///|//)', re.MULTILINE).search(content, index)
    if not match:
        return None
    token = match.group(1)
    start = end = match.start(1)
    while True:
        end = _next_line(content, end)
        if content[end:end + len(token)] != token:
            break
    return '\n'.join(line[len(token) + 1:] for line in content[start:end].splitlines())


_COPYRIGHT_RE = re.compile(
    r'^[^\n\r]?\s*(?:\\copyright\s*)?copyright(?:\s+\(c\))?\s+'
    r'((?:\d{4}|\d{4}-\d{4})(?:,\s*(?:\d{4}|\d{4}-\d{4}))*),?\s+([^\n\r]+)$',
    re.DOTALL | re.MULTILINE | re.IGNORECASE)


def _flat(text: str) -> str:
    return ' '.join(text.split())


def copyright_problem(content: str) -> str | None:
    """
    Check one Python source the way ``ament_copyright`` does for the apache2 license.

    Returns
    -------
    str or None
        None when the first comment block (after a shebang/coding line) holds a copyright
        notice followed by the Apache-2.0 notice; else what ament_copyright would say.

    """
    if not content:
        return None  # ament_copyright: 'file empty', not an error
    block = _comment_block(content, _past_empty_lines(content, _past_shebang_and_coding(content)))
    if block is None:
        return 'could not find copyright notice'
    remaining, found = block, False
    while True:
        match = _COPYRIGHT_RE.search(remaining)
        if not match:
            break
        found, remaining = True, remaining[match.end(2):]
    if not found:
        return 'could not find copyright notice'
    text, last = _flat('{copyright}' + remaining), -1
    for section in filter(None, _flat(APACHE2_HEADER).split('{copyright}')):
        index = text.find(section.strip())
        if index == -1 or index <= last:
            return 'license=<unknown> (not the Apache-2.0 notice)'
        last = index
    return None


# ament_copyright's apache2 LICENSE template (template/apache2_license.txt, the Apache-2.0
# text), whitespace-normalised: its first words, length and SHA-256.
_LICENSE_START = 'Apache License Version 2.0, January 2004'
_LICENSE_LENGTH = 10221
_LICENSE_SHA256 = '0ffddef9e48f8a09aed5caf2d44f7ba1c1be2d9b8e0a6f693b1635b2d5566645'
# template/apache2_contributing.txt
APACHE2_CONTRIBUTING = """Any contribution that you make to this repository will
be under the Apache 2 License, as dictated by that
[license](http://www.apache.org/licenses/LICENSE-2.0.html):

~~~
5. Submission of Contributions. Unless You explicitly state otherwise,
   any Contribution intentionally submitted for inclusion in the Work
   by You to the Licensor shall be under the terms and conditions of
   this License, without any additional terms or conditions.
   Notwithstanding the above, nothing herein shall supersede or modify
   the terms of any separate license agreement you may have executed
   with Licensor regarding such Contributions.
~~~
"""
_SOURCE_EXTENSIONS = ('.c', '.cc', '.cpp', '.cxx', '.h', '.hh', '.hpp', '.hxx', '.cmake', '.py')


def _is_repository_root(path: Path) -> bool:
    return (path / '.git').exists() or (path / '.hg').exists()


def _license_problem(content: str) -> str | None:
    flat = _flat(content)
    index = flat.find(_LICENSE_START)
    found = flat[index:index + _LICENSE_LENGTH] if index >= 0 else ''
    if hashlib.sha256(found.encode('utf-8')).hexdigest() != _LICENSE_SHA256:
        return '<unknown> (not the Apache-2.0 text)'
    return None


def copyright_report(paths: list[Path]) -> list[str]:
    """
    Check ``paths`` as ``ament_copyright PATHS`` does, for the apache2 license only.

    Source files (C/C++, CMake, Python) under each path, skipping directories starting with
    ``.`` or ``_``, directories with an ``AMENT_IGNORE`` file and a ``setup.py`` beside a
    ``package.xml``; at a repository root (``.git``), also ``LICENSE`` (the Apache-2.0 text)
    and ``CONTRIBUTING.md`` (ament's apache2 contributing text).

    Returns
    -------
    list of str
        One ``'path: problem'`` line per file that ament_copyright would report.

    """
    sources, repo_files = set(), set()
    for path in paths:
        if path.is_dir():
            for dirpath, dirnames, filenames in os.walk(path):
                here = Path(dirpath)
                if 'AMENT_IGNORE' in dirnames + filenames:
                    dirnames[:] = []
                    continue
                if _is_repository_root(here):
                    repo_files.update({here / 'LICENSE', here / 'CONTRIBUTING.md'})
                dirnames[:] = [d for d in dirnames if d[0] not in '._']
                for name in filenames:
                    if name == 'setup.py' and (here / 'package.xml').exists():
                        continue
                    if name.endswith(_SOURCE_EXTENSIONS):
                        sources.add(here / name)
        elif path.is_file() and path.name.endswith(_SOURCE_EXTENSIONS):
            sources.add(path)
    errors = []
    for path in sorted(sources - repo_files):
        problem = copyright_problem(path.read_text(encoding='utf-8'))
        if problem:
            errors.append(f'{os.path.normpath(path)}: {problem}')
    for path in sorted(repo_files):
        if not path.exists() or not path.read_text(encoding='utf-8').strip():
            errors.append(f'{os.path.normpath(path)}: file not found or empty')
            continue
        content = path.read_text(encoding='utf-8')
        if path.name == 'LICENSE':
            problem = _license_problem(content)
        else:
            problem = (None if _flat(APACHE2_CONTRIBUTING) in _flat(content)
                       else '<unknown> (not the apache2 contributing text)')
        if problem:
            errors.append(f'{os.path.normpath(path)}: {problem}')
    return errors


def header_comment() -> str:
    """Return the header comment block ``ament_copyright --add-missing`` writes (no newline)."""
    text = APACHE2_HEADER.format(copyright=f'Copyright {YEAR} {HOLDER}')
    return '\n'.join('#' + (' ' + line if line else '') for line in text.split('\n'))


def fix_header(content: str) -> str:
    """Add the copyright/license header after any shebang/coding line, unless present."""
    if not content or copyright_problem(content) is None:
        return content
    if _COPYRIGHT_RE.search(_comment_block(content, _past_empty_lines(
            content, _past_shebang_and_coding(content))) or ''):
        return content  # a notice with another license: for a human to decide
    begin = _past_shebang_and_coding(content)
    end = _past_empty_lines(content, begin)
    block = header_comment() + '\n\n'
    if begin > 0:
        block = '\n' + block
    return content[:begin] + block + content[end:]


# --------------------------------------------------------------------------------------------
# Syntax-tree comparison


def _docstring_owners(tree: ast.AST):
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            if (node.body and isinstance(node.body[0], ast.Expr)
                    and isinstance(node.body[0].value, ast.Constant)
                    and isinstance(node.body[0].value.value, str)):
                yield node.body[0].value


def _normalise(tree: ast.Module, *, docstrings=False, imports=False, literals=False) -> str:
    # Changes ``tree`` in place: callers pass a tree parsed for this comparison.
    if docstrings:
        for const in _docstring_owners(tree):
            const.value = _summary_first(const.value)
    if imports:
        # A block of consecutive imports stands for the set of names it binds.
        body, run = [], []
        for stmt in tree.body + [None]:
            if isinstance(stmt, (ast.Import, ast.ImportFrom)):
                run.append(stmt)
                continue
            if run:
                bound = sorted({_alias_key(s, a) for s in run for a in s.names}, key=repr)
                body.append(ast.Expr(ast.Constant(repr(bound))))
            run = []
            if stmt is not None:
                body.append(stmt)
        tree.body = body
    if literals:
        tree = _Literals().visit(tree)
    return ast.dump(tree, include_attributes=False)


def _alias_key(stmt: ast.AST, alias: ast.alias) -> tuple:
    if isinstance(stmt, ast.ImportFrom):
        return ('from', stmt.level, stmt.module, alias.name, alias.asname)
    return ('import', alias.name, alias.asname)


def _merge_key(stmt: ast.AST) -> tuple:
    if isinstance(stmt, ast.ImportFrom):
        return ('from', stmt.level, stmt.module)
    return ('import', ast.dump(stmt))


def _summary_first(doc: str) -> str:
    lines = doc.split('\n')
    if len(lines) > 1 and lines[0].strip() == '' and lines[1].strip():
        return lines[1].strip() + '\n' + '\n'.join(lines[2:])
    return lines[0].strip() + '\n' + '\n'.join(lines[1:]) if len(lines) > 1 else doc


class _Literals(ast.NodeTransformer):
    """Rewrite dict()/list()/tuple() calls as displays, like step 1 does in the source."""

    def visit_Call(self, node):  # noqa: N802
        self.generic_visit(node)
        if _literal_call(node):
            if node.func.id == 'dict':
                return ast.Dict(keys=[ast.Constant(k.arg) for k in node.keywords],
                                values=[k.value for k in node.keywords])
            if node.func.id == 'list':
                return ast.List(elts=[], ctx=ast.Load())
            return ast.Tuple(elts=[], ctx=ast.Load())
        return node


def _checked(before: str, after: str, **what) -> str:
    """Return ``after`` if its syntax tree equals ``before``'s up to what the step may change."""
    if after == before:
        return after
    if _normalise(ast.parse(before), **what) != _normalise(ast.parse(after), **what):
        raise StepRejected(', '.join(what))
    return after


# --------------------------------------------------------------------------------------------
# Text edits by ast position (ast columns are UTF-8 byte offsets)


def _char_col(line: str, byte_col: int) -> int:
    return len(line.encode('utf-8')[:byte_col].decode('utf-8'))


def _apply(lines: list[str], edits) -> list[str]:
    """Apply ((row, col), (row, col), text) edits (1-based rows, char columns), last first."""
    text = ''.join(lines)
    starts = [0]
    for line in lines:
        starts.append(starts[-1] + len(line))
    for (r0, c0), (r1, c1), new in sorted(edits, reverse=True):
        text = text[:starts[r0 - 1] + c0] + new + text[starts[r1 - 1] + c1:]
    return text.splitlines(keepends=True)


# --------------------------------------------------------------------------------------------
# Step 1: C408


def _literal_call(node: ast.AST) -> bool:
    return (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
            and node.func.id in ('dict', 'list', 'tuple') and not node.args
            and (not node.keywords or (node.func.id == 'dict'
                                       and all(k.arg is not None for k in node.keywords))))


def _rebinds(tree: ast.AST, names: set[str]) -> set[str]:
    bound = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Name) and isinstance(node.ctx, (ast.Store, ast.Del)):
            bound.add(node.id)
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            bound.add(node.name)
        elif isinstance(node, ast.arg):
            bound.add(node.arg)
        elif isinstance(node, ast.alias):
            bound.add((node.asname or node.name).split('.')[0])
    return bound & names


def fix_literals(content: str) -> str:
    """Rewrite C408 calls as literals where the lines stay within 99 characters."""
    tree = ast.parse(content)
    shadowed = _rebinds(tree, {'dict', 'list', 'tuple'})
    lines = content.splitlines(keepends=True)
    calls = [n for n in ast.walk(tree) if _literal_call(n) and n.func.id not in shadowed]
    # Innermost first; an enclosing call is rewritten on the next run (positions move).
    inner = [c for c in calls
             if not any(o is not c and (o.lineno, o.col_offset) >= (c.lineno, c.col_offset)
                        and (o.end_lineno, o.end_col_offset) <= (c.end_lineno, c.end_col_offset)
                        for o in calls)]
    opening = {'dict': '{', 'list': '[', 'tuple': '('}
    closing = {'dict': '}', 'list': ']', 'tuple': ')'}
    for call in sorted(inner, key=lambda c: (c.lineno, c.col_offset), reverse=True):
        def col(row, byte_col):
            return _char_col(lines[row - 1], byte_col)
        start = (call.lineno, col(call.lineno, call.col_offset))
        paren = (call.func.end_lineno, col(call.func.end_lineno, call.func.end_col_offset))
        if lines[paren[0] - 1][paren[1]:paren[1] + 1] != '(':
            continue
        end = (call.end_lineno, col(call.end_lineno, call.end_col_offset))
        if lines[end[0] - 1][end[1] - 1] != ')':
            continue
        edits = [((end[0], end[1] - 1), end, closing[call.func.id]),
                 (start, (paren[0], paren[1] + 1), opening[call.func.id])]
        for kw in call.keywords:
            edits.append(((kw.lineno, col(kw.lineno, kw.col_offset)),
                          (kw.value.lineno, col(kw.value.lineno, kw.value.col_offset)),
                          f"'{kw.arg}': "))
        # Continuation lines: visual indent (aligned one past the bracket) moves left with the
        # bracket; hanging indent stays. Any other layout (a bracket opened inside a keyword
        # value and continued below) would come out misaligned: left for a hand fix.
        conts = [r for r in range(call.lineno, call.end_lineno) if lines[r].strip()]
        indents = {r: len(lines[r]) - len(lines[r].lstrip(' ')) for r in conts}
        shift = paren[1] - start[1]
        hanging = not lines[paren[0] - 1][paren[1] + 1:].strip()
        if hanging:
            body = [r for r in conts if not lines[r].lstrip().startswith(')')]
            if len({indents[r] for r in body}) > 1:
                continue
            dedent = []
        elif all(indents[r] == paren[1] + 1 for r in conts):
            dedent = conts
        else:
            continue
        new = _apply(lines, edits)
        for r in dedent:
            new[r] = new[r][shift:]
        rows = range(call.lineno - 1, call.end_lineno)
        if all(len(new[r].rstrip('\r\n')) <= MAX_LINE for r in rows):
            lines = new
    return _checked(content, ''.join(lines), literals=True)


# --------------------------------------------------------------------------------------------
# Step 2: import order (flake8-import-order, google style)


def _import_style():
    from flake8_import_order import ImportVisitor
    from flake8_import_order.styles import Google
    return ImportVisitor, Google


def _format_from(node: ast.ImportFrom) -> str:
    _, google = _import_style()
    parts = [a.name + (f' as {a.asname}' if a.asname else '')
             for a in sorted(node.names, key=lambda a: google.name_key(a.name))]
    module = '.' * node.level + (node.module or '')
    line = f'from {module} import {", ".join(parts)}'
    if len(line) <= MAX_LINE:
        return line + '\n'
    head = f'from {module} import ('
    out, current = [], head
    for i, part in enumerate(parts):
        piece = part + (', ' if i < len(parts) - 1 else ')')
        if current != head and len(current) + len(piece.rstrip()) > MAX_LINE:
            out.append(current.rstrip())
            current = ' ' * len(head)
        current += piece
    out.append(current)
    return '\n'.join(out) + '\n'


def _has_comment(source: str) -> bool:
    try:
        return any(t.type == tokenize.COMMENT
                   for t in tokenize.generate_tokens(io.StringIO(source).readline))
    except (tokenize.TokenError, SyntaxError):
        return True


def fix_imports(content: str, problems: list[str]) -> str:
    """Sort each block of consecutive top-level imports that flake8-import-order flags."""
    visitor_cls, google = _import_style()
    tree = ast.parse(content)
    visitor = visitor_cls([], [])
    visitor.visit(tree)
    classified = {c.lineno: c for c in visitor.imports}
    lines = content.splitlines(keepends=True)

    runs, run = [], []
    for stmt in tree.body:
        is_import = isinstance(stmt, (ast.Import, ast.ImportFrom)) and stmt.lineno in classified
        if is_import and run and all(not line.strip() or line.lstrip().startswith('#')
                                     for line in lines[run[-1].end_lineno:stmt.lineno - 1]) \
                and stmt.lineno > run[-1].end_lineno:
            run.append(stmt)
            continue
        if run:
            runs.append(run)
        run = [stmt] if is_import else []
    if run:
        runs.append(run)

    edits, previous_last = [], None
    for run in runs:
        info = [classified[s.lineno] for s in run]
        if previous_last is not None and google.import_key(previous_last) > google.import_key(
                min(info, key=google.import_key)):
            problems.append(f'line {run[0].lineno}: imports above it (separated by code) '
                            'sort after it; move them by hand')
        previous_last = max(info, key=google.import_key)
        names_ok = all(google.sorted_names(c.names) == c.names for c in info)
        order_ok = all(google.import_key(a) <= google.import_key(b)
                       for a, b in zip(info, info[1:]))
        groups_ok = all(google.same_section(a, b) or any(
            not line.strip() for line in lines[s.end_lineno:t.lineno - 1])
            for a, b, s, t in zip(info, info[1:], run, run[1:]))
        if any(c.type < 0 for c in info):
            problems.append(f'line {run[0].lineno}: one import statement mixes groups')
            continue
        # The same module imported twice in a block (what a merge can leave): one statement.
        bound = [_alias_key(stmt, a) for stmt in run for a in stmt.names]
        unique = len(set(bound)) == len(bound)
        if names_ok and order_ok and groups_ok and unique:
            continue
        units, first_of = [], {}
        for i, (stmt, cls) in enumerate(zip(run, info)):
            above = lines[run[i - 1].end_lineno:stmt.lineno - 1] if i else []
            comments = [line for line in above if line.strip()]
            text = ''.join(lines[stmt.lineno - 1:stmt.end_lineno])
            key = _merge_key(stmt)
            repeats = {_alias_key(stmt, a) for a in stmt.names} & {
                _alias_key(units[first_of[key]][4], a) for a in units[first_of[key]][4].names
            } if key in first_of else set()
            if repeats:
                j = first_of[key]
                if comments or _has_comment(text) or _has_comment(units[j][3]):
                    problems.append(f'line {stmt.lineno}: a repeated import with a comment; '
                                    'merge it by hand')
                    break
                if isinstance(stmt, ast.ImportFrom):
                    old = units[j][4]
                    aliases = list({(a.name, a.asname): a
                                    for a in old.names + stmt.names}.values())
                    merged = ast.ImportFrom(module=stmt.module, names=aliases, level=stmt.level)
                    merged_cls = units[j][2]._replace(names=[a.name for a in aliases])
                    units[j] = [google.import_key(merged_cls), units[j][1], merged_cls,
                                _format_from(merged), merged]
                continue
            first_of.setdefault(key, len(units))
            if google.sorted_names(cls.names) != cls.names:
                if _has_comment(text):
                    problems.append(f'line {stmt.lineno}: names out of order in an import '
                                    'with a comment inside; sort them by hand')
                    break
                text = _format_from(stmt)
            if not text.endswith('\n'):
                text += '\n'
            units.append([google.import_key(cls), i, cls, ''.join(comments) + text, stmt])
        else:
            units.sort(key=lambda u: (u[0], u[1]))
            out, prev = [], None
            for _, _, cls, text, _ in units:
                if prev is not None and not google.same_section(prev, cls):
                    out.append('\n')
                out.append(text)
                prev = cls
            end_line = lines[run[-1].end_lineno - 1]
            edits.append(((run[0].lineno, 0), (run[-1].end_lineno, len(end_line)),
                          ''.join(out)))
    new = ''.join(_apply(lines, edits)) if edits else content
    return _checked(content, new, imports=True)


# --------------------------------------------------------------------------------------------
# Step 3: D213


_START_TRIPLE = {'"""', "'''", 'u"""', "u'''", 'r"""', "r'''", 'ur"""', "ur'''"}


def fix_docstrings(content: str) -> str:
    """Move the summary of each multi-line docstring to the line after the opening quotes."""
    tree = ast.parse(content)
    targets = {(c.lineno, c.col_offset, c.end_lineno, c.end_col_offset)
               for c in _docstring_owners(tree)}
    lines = content.splitlines(keepends=True)
    edits = []
    for tok in tokenize.generate_tokens(io.StringIO(content).readline):
        if tok.type != tokenize.STRING:
            continue
        row, col = tok.start
        line = lines[row - 1]
        key = (row, len(line[:col].encode('utf-8')), tok.end[0],
               len(lines[tok.end[0] - 1][:tok.end[1]].encode('utf-8')))
        if key not in targets:
            continue
        text = tok.string
        prefix = re.match(r'[rRuU]*', text).group(0)
        quote = text[len(prefix):len(prefix) + 3]
        if quote not in ('"""', "'''") or '\n' not in ast.literal_eval(text):
            continue
        first = text.split('\n')[0]
        if first.strip().lower() in _START_TRIPLE:
            continue
        after = col + len(prefix) + 3
        rest = line[after:]
        skip = len(rest) - len(rest.lstrip(' \t'))
        edits.append(((row, after), (row, after + skip), '\n' + ' ' * col))
    new = ''.join(_apply(lines, edits)) if edits else content
    return _checked(content, new, docstrings=True)


# --------------------------------------------------------------------------------------------
# Quotes (flake8-quotes' defaults, as under ament)


def fix_quotes(content: str) -> str:
    """
    Use single quotes for one-line strings (Q000) and double for triple-quoted ones (Q001/Q002).

    Only where the string's text does not change: no backslash, no quote of the new kind inside
    (a triple-quoted string may hold single double quotes, not at its end, unless an f-string).
    Python >= 3.12 tokenises f-strings in pieces: there they keep their quotes.
    """
    lines = content.splitlines(keepends=True)
    edits = []
    for tok in tokenize.generate_tokens(io.StringIO(content).readline):
        if tok.type != tokenize.STRING:
            continue
        prefix = re.match(r'[rRbBuUfF]*', tok.string).group(0)
        text = tok.string[len(prefix):]
        if text.startswith("'''"):
            inner = text[3:-3]
            if ('"' in inner[-1:] or '"""' in inner or '\\' in inner
                    or ('f' in prefix.lower() and '"' in inner)):
                continue
            new = '"""' + inner + '"""'
        elif text.startswith('"') and not text.startswith('"""'):
            inner = text[1:-1]
            if "'" in inner or '\\' in inner:
                continue
            new = "'" + inner + "'"
        else:
            continue
        (r0, c0), (r1, c1) = tok.start, tok.end
        edits.append(((r0, c0 + len(prefix)), (r1, c1), new))
    new_content = ''.join(_apply(lines, edits)) if edits else content
    return _checked(content, new_content)


# --------------------------------------------------------------------------------------------


A005_NOQA = ('# noqa: A005 (a subpackage of contact_detector: the standard library module '
             'stays reachable)')


def fix_stdlib_name(content: str, path: Path) -> str:
    """
    Mark a module named like a standard library module (A005, reported on line 1).

    flake8-builtins reports ``contact_detector/io/__init__.py`` as shadowing ``io``; a
    subpackage shadows nothing, so line 1 gets a ``# noqa: A005`` comment line (kept
    contiguous with the copyright block below it, which ament_copyright still finds).
    """
    name = path.parent.name if path.name == '__init__.py' else path.stem
    first = content.split('\n', 1)[0]
    if (name not in sys.stdlib_module_names or not content or first.startswith('#!')
            or ('noqa' in first and 'A005' in first)):
        return content
    return A005_NOQA + '\n' + content


def fix_text(content: str, problems: list[str], path: Path = Path('module.py')) -> str:
    """Run every step on one file's text; return the new text."""
    for step in (fix_literals, lambda c: fix_imports(c, problems), fix_docstrings,
                 fix_quotes):
        try:
            content = step(content)
        except StepRejected as err:
            problems.append(f'a step was dropped: its result changed more than {err}')
    return fix_stdlib_name(fix_header(content), path)


def main(argv=None) -> int:
    """Fix (or with --check, list) the files; return 1 if --check found work or on problems."""
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('files', nargs='*', type=Path,
                        help='files to fix (default: every Python file of the package)')
    parser.add_argument('--check', action='store_true', help='change nothing, list the files')
    args = parser.parse_args(argv)
    files = args.files or python_files(ROOT)
    changed, rc = [], 0
    for path in files:
        before = path.read_text(encoding='utf-8')
        problems: list[str] = []
        try:
            after = fix_text(before, problems, path)
        except SyntaxError as err:
            problems.append(f'not parsed: {err}')
            after = before
        for problem in problems:
            print(f'{path}: {problem}', file=sys.stderr)
            rc = 1
        if after != before:
            changed.append(path)
            if not args.check:
                path.write_text(after, encoding='utf-8')
    verb = 'would change' if args.check else 'changed'
    print(f'lint_fix: {verb} {len(changed)} of {len(files)} files')
    for path in changed:
        print(f'  {path}')
    if args.check and changed:
        rc = 1
    return rc


if __name__ == '__main__':
    sys.exit(main())
