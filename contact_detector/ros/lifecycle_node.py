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
The managed (lifecycle) variant of the contact detector node.

Same interface, parameters and processing as :class:`~contact_detector.ros.node.
ContactDetectorNode` (both run :class:`~contact_detector.ros.node.DetectorWiring`), driven by
the ROS 2 lifecycle (``ros2 lifecycle set /contact_detector configure`` ..., or a lifecycle
manager)::

    unconfigured --configure--> inactive --activate--> active
                 <--cleanup---           <-deactivate-

configure
    reads and checks the parameters, loads and checks the model, builds the detector, creates
    the publishers and the ``~/arm`` / ``~/reset`` services. A bad parameter or model fails
    the transition (the node stays unconfigured) with one ERROR line saying what to change.
activate
    resets the detector's stream state (a warm-up follows), subscribes to the inputs, starts
    ``/diagnostics`` and enables the publishers.
deactivate
    unsubscribes (nothing is decided, so nothing is released while inactive), stops
    ``/diagnostics`` and disables the publishers.
cleanup, shutdown
    release everything configure made (the model included).

See ``docs/node.md``.
"""

import sys
from typing import Any, Optional

from contact_detector.errors import ConfigError, ModelError
from contact_detector.ros.node import DetectorWiring, spin_node
from contact_detector.ros.params import config_from_values, current_values, declare_all
from rclpy.executors import SingleThreadedExecutor
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from rclpy.node import Node


class ContactDetectorLifecycleNode(DetectorWiring, LifecycleNode):
    """
    Managed ROS 2 node around :class:`ContactDetector`; starts unconfigured.

    Parameters
    ----------
    node_name : str
        Node name (default ``contact_detector``).
    **kwargs
        Passed to :class:`rclpy.lifecycle.LifecycleNode` (``context``,
        ``parameter_overrides``, ...).

    Raises
    ------
    ConfigError
        A parameter override has the wrong type or is out of range (declaration; the other
        checks run at configure).

    """

    def __init__(self, node_name: str = 'contact_detector', **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        self.bundle = None
        self.ft_bundle = None
        self.detector = None
        self.config = None
        self.diagnostics_timer = None
        self._pending = None
        try:
            declare_all(self)
        except BaseException:
            self.destroy_node()
            raise
        self.add_on_set_parameters_callback(self._validate_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)

    # --- transitions -----------------------------------------------------------------------------

    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Check the parameters, load the model, create the publishers and services."""
        try:
            self._load(config_from_values(current_values(self)), None)
            self._create_outputs(self.create_lifecycle_publisher)
        except (ConfigError, ModelError) as err:
            self.get_logger().error(f'configure failed: {err}')
            self._unload()
            return TransitionCallbackReturn.FAILURE
        self._log_loaded()
        return super().on_configure(state)

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Reset the stream state, subscribe to the inputs, enable the publishers."""
        self.detector.reset()
        # Waiting for input again: no stale-input warning until an input has arrived.
        for stream in (self.audio, self.wrench):
            stream.last_rx = stream.last_stamp = None
        self._started.clear()
        self._create_inputs()
        self.get_logger().info('active: release '
                               f'{"armed" if self.detector.armed else "disarmed"}')
        return super().on_activate(state)

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Unsubscribe (no decisions, no release), stop diagnostics, disable the publishers."""
        self._destroy_inputs()
        self.get_logger().info('inactive: inputs unsubscribed, no release')
        return super().on_deactivate(state)

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Destroy the publishers and services; forget the model and the detector."""
        self._destroy_outputs(self.destroy_lifecycle_publisher)
        self._unload()
        return super().on_cleanup(state)

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Release whatever the current state holds."""
        if self.diagnostics_timer is not None:
            self._destroy_inputs()
        if self.detector is not None:
            self._destroy_outputs(self.destroy_lifecycle_publisher)
        self._unload()
        return super().on_shutdown(state)

    def _unload(self) -> None:
        self.bundle = self.ft_bundle = self.detector = self.config = None


def main(args: Optional[list] = None) -> int:
    """
    Run the managed node (``ros2 run contact_detector contact_detector_lifecycle_node``).

    It starts unconfigured and waits for its transitions; rclpy's SingleThreadedExecutor runs
    it (``executor.*`` parameters are not used). Returns the exit code.
    """
    def single_threaded(node: Node) -> SingleThreadedExecutor:
        executor = SingleThreadedExecutor()
        executor.add_node(node)
        return executor

    return spin_node(args=args, make_node=ContactDetectorLifecycleNode,
                     make_exec=single_threaded)


if __name__ == '__main__':
    sys.exit(main())
