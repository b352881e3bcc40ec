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
An opt-in executor that serves the sensor subscriptions from a small wait set.

**Private rclpy API.** It builds its wait set with ``rclpy.impl.implementation_singleton`` (the
C extension behind rclpy's executors) and reads executor and subscription internals
(``_guard``, ``_sigint_gc``, ``_context``, ``_is_shutdown``, ``_callback_type``). An rclpy
update can change any of them, so the node's default executor is rclpy's public
:class:`~rclpy.executors.SingleThreadedExecutor` and this one runs only with
``executor.type: hot_path``. It was checked with the rclpy versions in
:data:`CHECKED_RCLPY_VERSIONS` (``test/test_hot_path_executor.py`` fails on any other, and
:func:`contact_detector.ros.node.make_executor` logs a warning); this module is imported only
when that executor is asked for.

rclpy's :class:`~rclpy.executors.SingleThreadedExecutor` rebuilds its wait set from every entity
of every node (parameter services, QoS event handlers, timers, ...) on each wake-up and wraps
each callback in a task: about 0.3-0.5 ms of Python per message, 10 % of a core for 100 Hz
audio chunks plus 100 Hz wrench messages before any detection work. :class:`HotPathExecutor`
waits on the hot subscriptions only (plus the executor's wake-up and SIGINT guard conditions)
and calls their callbacks directly; everything else (services, parameter updates, timers,
``/clock``, ``audio_info``) is served by the stock executor every ``poll_s`` at the latest.
Callbacks are exactly those of the stock executor.

Fewer wake-ups: each wake-up of a process that slept costs far more CPU than the same work done
right after other work (cold caches, ~0.5 ms per message here). ``lazy`` subscriptions (the
wrench) do not wake the executor by themselves: they are waited on only while ``wanted()`` says
so (an audio frame waits for F/T data) or once ``lazy_max_s`` has passed since they were last
served (a dead audio stream still gets its wrench handled, before the queue overflows). Every
wake-up takes all queued messages of the lazy subscriptions first, then of the others, so the
wrench samples that arrived with an audio chunk are there when the chunk is processed.
"""

from contextlib import ExitStack
from importlib import metadata
import time
from typing import Callable, Optional, Sequence
from xml.etree import ElementTree

from rclpy.context import Context
from rclpy.exceptions import InvalidHandle
from rclpy.executors import (ConditionReachedException, ExternalShutdownException,
                             ShutdownException, SingleThreadedExecutor, TimeoutException)
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.subscription import Subscription

RCLError = _rclpy.RCLError

#: rclpy versions whose private API this executor was checked with (its tests pass).
CHECKED_RCLPY_VERSIONS = ('7.1.5',)

#: At most this many stock callbacks are served per poll (bounds a burst of service calls).
MAX_STOCK_CALLBACKS_PER_POLL = 50
#: At most this many messages are taken from one subscription per wake-up (bounds a burst).
MAX_TAKES_PER_WAKE = 1000


def rclpy_version() -> Optional[str]:
    """
    Return the installed rclpy's version, or None where it cannot be told.

    From the Python distribution's metadata (the PyPI wheels), else from rclpy's
    ``package.xml`` in the ament index (a ROS installation).
    """
    try:
        return metadata.version('rclpy')
    except metadata.PackageNotFoundError:
        pass
    try:
        from ament_index_python.packages import get_package_share_directory
        root = ElementTree.parse(f'{get_package_share_directory("rclpy")}/package.xml')
    except (ImportError, LookupError, OSError, ElementTree.ParseError):
        return None         # no ament index, or rclpy not in it
    return root.findtext('version')


class HotPathExecutor(SingleThreadedExecutor):
    """
    Single-threaded executor with a fast path for chosen subscriptions.

    Parameters
    ----------
    hot : sequence of Subscription
        Subscriptions served from the small wait set (the sensor inputs).
    poll_s : float
        Longest time between two passes of the stock executor, s (service, parameter, timer
        and other callbacks wait at most this long).
    lazy : sequence of Subscription
        Those of ``hot`` that do not wake the executor by themselves (see the module
        docstring); their queued messages are taken first at every wake-up.
    wanted : callable, optional
        Returns True while the lazy subscriptions must wake the executor; default never.
    lazy_max_s : float
        Longest time between two passes over the lazy subscriptions, s (keep it below the time
        their queue depth lasts).
    context : Context, optional
        The rclpy context.

    """

    def __init__(self, *, hot: Sequence[Subscription], poll_s: float = 0.02,
                 lazy: Sequence[Subscription] = (),
                 wanted: Optional[Callable[[], bool]] = None, lazy_max_s: float = 0.05,
                 context: Optional[Context] = None) -> None:
        super().__init__(context=context)
        lazy = [sub for sub in lazy if sub in hot]
        # Lazy ones first: their messages are taken before the others'.
        self._hot = lazy + [sub for sub in hot if sub not in lazy]
        self._hot_ids = {id(sub) for sub in self._hot}
        self._n_lazy = len(lazy)
        self._lazy_ids = {id(sub) for sub in lazy}
        self._wanted = wanted
        self._lazy_max_s = float(lazy_max_s)
        self._lazy_due = 0.0
        self._poll_s = float(poll_s)
        self._next_stock = 0.0

    def can_execute(self, entity) -> bool:
        """Leave the hot subscriptions out of the stock executor's wait set: served here only."""
        return id(entity) not in self._hot_ids and super().can_execute(entity)

    def spin_once(self, timeout_sec: Optional[float] = None) -> None:
        """Serve due stock callbacks, then wait for hot messages until the next stock pass."""
        try:
            self._spin_once(timeout_sec)
        except (RCLError, InvalidHandle):
            # SIGINT shuts the context down at any moment, e.g. while a wait set is made.
            if self._context.ok():
                raise
            raise ExternalShutdownException()

    def _spin_once(self, timeout_sec: Optional[float]) -> None:
        now = time.monotonic()
        if now >= self._next_stock:
            self._next_stock = now + self._poll_s
            self._serve_stock()
        now = time.monotonic()
        until = self._next_stock
        wake_lazy = (not self._n_lazy or now >= self._lazy_due
                     or (self._wanted is not None and self._wanted()))
        if not wake_lazy:
            until = min(until, self._lazy_due)
        wait = max(0.0, until - now)
        if timeout_sec is not None and timeout_sec >= 0:
            wait = min(wait, timeout_sec)
        self._serve_hot(wait, wake_lazy)

    def _serve_stock(self) -> None:
        for _ in range(MAX_STOCK_CALLBACKS_PER_POLL):
            try:
                handler, _, _ = self.wait_for_ready_callbacks(timeout_sec=0)
            except (ShutdownException, TimeoutException, ConditionReachedException):
                return
            handler()
            if handler.exception() is not None:
                raise handler.exception()

    def _serve_hot(self, timeout_s: float, wake_lazy: bool) -> None:
        if self._is_shutdown:
            return
        with ExitStack() as stack:
            hot, waited = [], []
            for sub in self._hot:
                try:
                    stack.enter_context(sub.handle)
                    hot.append(sub)
                    if wake_lazy or id(sub) not in self._lazy_ids:
                        waited.append(sub)
                except InvalidHandle:
                    pass
            guards = []
            for guard in (self._guard, self._sigint_gc):
                if guard is not None:
                    stack.enter_context(guard.handle)
                    guards.append(guard.handle)
            stack.enter_context(self._context.handle)
            wait_set = _rclpy.WaitSet(len(waited), len(guards), 0, 0, 0, 0,
                                      self._context.handle)
            wait_set.clear_entities()
            for sub in waited:
                wait_set.add_subscription(sub.handle)
            for guard in guards:
                wait_set.add_guard_condition(guard)
            wait_set.wait(int(timeout_s * 1e9))
            if self._is_shutdown:
                return
            if not self._context.ok():
                raise ExternalShutdownException()
            ready = {id(sub) for index, sub in enumerate(waited)
                     if wait_set.is_ready('subscription', index)}
            if not ready and not (self._n_lazy and time.monotonic() >= self._lazy_due):
                return              # a guard condition or the stock poll's time
            if self._n_lazy:
                self._lazy_due = time.monotonic() + self._lazy_max_s
            for sub in hot:
                # Lazy subscriptions are polled at every wake-up, the others when ready.
                if id(sub) not in ready and id(sub) not in self._lazy_ids:
                    continue
                for _ in range(MAX_TAKES_PER_WAKE):
                    taken = sub.handle.take_message(sub.msg_type, sub.raw)
                    if taken is None:
                        break
                    if sub._callback_type is Subscription.CallbackType.MessageOnly:
                        sub.callback(taken[0])
                    else:
                        sub.callback(*taken)
