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
is set (the README's commands set it).
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

    import rclpy
    from rclpy.executors import ExternalShutdownException

    from contact_detector.ros.player import BagPlayer, read_recording

    try:
        records = read_recording(args.bag, topics=args.topics)
    except ContactDetectorError as err:
        print(f'contact-detector replay: {err}', file=sys.stderr)
        return 1
    if not records:
        print(f'contact-detector replay: {args.bag} has no messages', file=sys.stderr)
        return 1
    rclpy.init()
    node = rclpy.create_node('contact_detector_replay')
    try:
        player = BagPlayer(node=node, rate=args.rate, clock=args.clock, restamp=args.restamp,
                           log=node.get_logger().warning)
        duration = (records[-1].log_ns - records[0].log_ns) * 1e-9
        if args.wait_for_subscribers > 0:
            lonely = player.wait_for_subscribers(records, timeout_s=args.wait_for_subscribers)
            if lonely:
                print(f'no subscriber after {args.wait_for_subscribers:g} s on '
                      f'{", ".join(lonely)}; playing anyway', flush=True)
        while True:
            print(f'playing {args.bag.name}: {len(records)} messages, {duration:.1f} s '
                  f'at {args.rate:g}x', flush=True)
            player.play(records)
            if not args.loop:
                break
        if not player.flush(timeout_s=5.0):
            print('some subscribers did not acknowledge the last messages within 5 s',
                  flush=True)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except ContactDetectorError as err:
        print(f'contact-detector replay: {err}', file=sys.stderr)
        return 1
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
