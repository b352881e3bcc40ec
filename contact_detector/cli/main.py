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

"""``contact-detector COMMAND ...``: dispatch to one module per command."""

import importlib
import sys
from typing import Optional, Sequence

#: command -> (module, one-line help)
COMMANDS = {
    'demo': ('demo', 'simulate trials, run the node live on them, print a verdict per trial'),
    'simulate': ('simulate', 'write simulated glass-placing trials as rosbag2 + manifest'),
    'plot': ('plot', "plot a bag like the paper's figure 4"),
    'features': ('features', 'run the feature core on a generated signal and report it'),
    'train': ('train', "train the contact forest on bags (the paper's protocol)"),
    'detect': ('detect', "run the node's processing on bags, write JSONL decisions"),
    'label': ('label', "propose each recording's contact onset (hindsight), write a labels CSV"),
    'evaluate': ('evaluate', 'event metrics of the forest and the baselines against truth'),
    'replay': ('replay', 'publish a bag into the live ROS graph with its original timing'),
    'sweep': ('sweep', 'sweep feature and decision settings on held-out trials'),
    'convert-model': ('convert_model', 'convert a joblib/skops model to the npz format'),
}


def usage() -> str:
    """Return the top-level help text."""
    width = max(len(c) for c in COMMANDS)
    lines = ['usage: contact-detector COMMAND [options]', '', 'commands:']
    lines += [f'  {name:<{width}}  {text}' for name, (_, text) in COMMANDS.items()]
    lines += ['', 'Run "contact-detector COMMAND --help" for the options of a command.']
    return '\n'.join(lines)


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run ``contact-detector``; return the exit status."""
    args = list(sys.argv[1:] if argv is None else argv)
    if not args or args[0] in ('-h', '--help'):
        print(usage())
        return 0 if args else 2
    command, rest = args[0], args[1:]
    if command not in COMMANDS:
        print(f'contact-detector: unknown command {command!r}\n\n{usage()}', file=sys.stderr)
        return 2
    module = importlib.import_module(f'contact_detector.cli.{COMMANDS[command][0]}')
    return int(module.main(rest) or 0)


if __name__ == '__main__':
    sys.exit(main())
