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
``contact-detector replay``: publish a bag into the live ROS graph with its original timing.

    contact-detector replay BAG [--rate R] [--loop] [--clock] [--restamp] [--topics T ...]
                                [--wait-for-subscribers S]

For machines without ``ros2 bag``. ``--clock`` publishes ``/clock`` with the bag time for nodes
running with ``use_sim_time:=true`` (the equivalent of ``ros2 bag play --clock``);
``--restamp`` shifts header stamps to this machine's time instead, for nodes on wall time.
``--loop`` starts again at the end: time jumps backwards, which the detector answers with a
reset. ``--wait-for-subscribers S`` creates every publisher first and waits up to S seconds
until each topic has a subscriber, so the start of the bag is not lost to DDS discovery (which
can take seconds). DDS stays on this machine only if ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``
is set (the README's commands set it). A damaged bag plays up to where it is readable, with one
warning naming the damage, as in the other commands; a bag with nothing readable is an error
(exit status 1). The player is :func:`contact_detector.ros.player.replay_bag`.
"""

import argparse
from pathlib import Path
import sys
from typing import Optional, Sequence

from contact_detector.errors import ContactDetectorError


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the command; return the exit status."""
    parser = argparse.ArgumentParser(prog='contact-detector replay', description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('bag', type=Path)
    parser.add_argument('--rate', type=float, default=1.0, help='playback speed factor')
    parser.add_argument('--loop', action='store_true', help='play again and again')
    parser.add_argument('--clock', action='store_true', help='publish /clock (bag time)')
    parser.add_argument('--restamp', action='store_true',
                        help='shift header stamps to the current time (rate 1 only)')
    parser.add_argument('--topics', nargs='+', default=None, help='only these topics')
    parser.add_argument('--wait-for-subscribers', type=float, default=0.0, metavar='S',
                        help='before playing, wait up to S seconds until every topic has a '
                             'subscriber (default 0: start at once)')
    args = parser.parse_args(argv)
    from contact_detector.ros.player import replay_bag

    try:
        replay_bag(bag=args.bag, rate=args.rate, loop=args.loop, clock=args.clock,
                   restamp=args.restamp, topics=args.topics,
                   wait_for_subscribers_s=args.wait_for_subscribers)
    except ContactDetectorError as err:
        print(f'contact-detector replay: {err}', file=sys.stderr)
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main())
