"""An executor that serves the sensor subscriptions from a small wait set.

rclpy's :class:`~rclpy.executors.SingleThreadedExecutor` rebuilds its wait set from every entity
of every node (parameter services, QoS event handlers, timers, ...) on each wake-up and wraps
each callback in a task: about 0.3-0.5 ms of Python per message, 10 % of a core for 100 Hz
audio chunks plus 100 Hz wrench messages before any detection work. :class:`HotPathExecutor`
waits on the hot subscriptions only (plus the executor's wake-up and SIGINT guard conditions)
and calls their callbacks directly; everything else (services, parameter updates, timers,
``/clock``, ``audio_info``) is served by the stock executor every ``poll_s`` at the latest.
Callbacks and their order are exactly those of the stock executor.
"""

from contextlib import ExitStack
import time
from typing import Optional, Sequence

from rclpy.context import Context
from rclpy.exceptions import InvalidHandle
from rclpy.executors import (ConditionReachedException, ExternalShutdownException,
                             ShutdownException, SingleThreadedExecutor, TimeoutException)
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.subscription import Subscription

#: At most this many stock callbacks are served per poll (bounds a burst of service calls).
MAX_STOCK_CALLBACKS_PER_POLL = 50


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
    context : Context, optional
        The rclpy context.

    """

    def __init__(self, *, hot: Sequence[Subscription], poll_s: float = 0.02,
                 context: Optional[Context] = None) -> None:
        super().__init__(context=context)
        self._hot = list(hot)
        self._poll_s = float(poll_s)
        self._next_stock = 0.0

    def spin_once(self, timeout_sec: Optional[float] = None) -> None:
        """Serve due stock callbacks, then wait for hot messages until the next stock pass."""
        now = time.monotonic()
        if now >= self._next_stock:
            self._next_stock = now + self._poll_s
            self._serve_stock()
        wait = max(0.0, self._next_stock - time.monotonic())
        if timeout_sec is not None and timeout_sec >= 0:
            wait = min(wait, timeout_sec)
        self._serve_hot(wait)

    def _serve_stock(self) -> None:
        for _ in range(MAX_STOCK_CALLBACKS_PER_POLL):
            try:
                handler, _, _ = self.wait_for_ready_callbacks(timeout_sec=0)
            except (ShutdownException, TimeoutException, ConditionReachedException):
                return
            handler()
            if handler.exception() is not None:
                raise handler.exception()

    def _serve_hot(self, timeout_s: float) -> None:
        if self._is_shutdown:
            return
        with ExitStack() as stack:
            hot = []
            for sub in self._hot:
                try:
                    stack.enter_context(sub.handle)
                    hot.append(sub)
                except InvalidHandle:
                    pass
            guards = []
            for guard in (self._guard, self._sigint_gc):
                if guard is not None:
                    stack.enter_context(guard.handle)
                    guards.append(guard.handle)
            stack.enter_context(self._context.handle)
            wait_set = _rclpy.WaitSet(len(hot), len(guards), 0, 0, 0, 0, self._context.handle)
            wait_set.clear_entities()
            for sub in hot:
                wait_set.add_subscription(sub.handle)
            for guard in guards:
                wait_set.add_guard_condition(guard)
            wait_set.wait(int(timeout_s * 1e9))
            if self._is_shutdown:
                return
            if not self._context.ok():
                raise ExternalShutdownException()
            for index, sub in enumerate(hot):
                if not wait_set.is_ready('subscription', index):
                    continue
                taken = sub.handle.take_message(sub.msg_type, sub.raw)
                if taken is None:
                    continue
                if sub._callback_type is Subscription.CallbackType.MessageOnly:
                    sub.callback(taken[0])
                else:
                    sub.callback(*taken)
