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
The node's parameters in rclpy: declaration with descriptors, and the frozen config.

The table of parameters and their checks are in :mod:`contact_detector.detection.parameters`
(no ROS import; the offline tools check a parameter file with the same code). Every parameter
is declared with a :class:`rcl_interfaces.msg.ParameterDescriptor` (description, numeric range,
read-only where a change at run time makes no sense), so ``ros2 param describe`` shows it and
rclpy refuses out-of-range or read-only updates itself. Choices and cross-parameter rules are
checked by :func:`config_from_values`, at start-up and for every run-time update; errors name
the parameter. ``params/contact_detector.yaml`` documents the same table.
"""

from typing import Any, Dict

from contact_detector.detection.parameters import (config_from_values, NodeConfig, PARAMS,
                                                   PARAMS_BY_NAME, ParamSpec)
from contact_detector.errors import ConfigError
from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rclpy.exceptions import ParameterException, ParameterUninitializedException
from rclpy.node import Node

__all__ = ['config_from_values', 'current_values', 'declare_all', 'declare_parameters',
           'descriptor', 'NodeConfig', 'PARAMS', 'PARAMS_BY_NAME', 'ParamSpec']


def descriptor(spec: ParamSpec) -> ParameterDescriptor:
    """
    Return the rclpy descriptor of one parameter: description, range, read-only flag.

    Floating-point parameters are dynamically typed, so that an integer (``-p
    audio.sample_rate:=16000``, ``sample_rate: 16000`` in a params file) is accepted;
    :func:`config_from_values` converts it to a float and refuses any other type, and
    checks the range for both (rclpy checks ``floating_point_range`` for floats only). So are
    double arrays (``wrench.bias: [0, 0, 0, 0, 0, 0]``), whose elements it checks.

    Parameters
    ----------
    spec : ParamSpec
        The parameter.

    Returns
    -------
    ParameterDescriptor

    """
    # an array too: [0, 0, 0, 0, 0, 0] in a params file is an integer array
    desc = ParameterDescriptor(description=spec.description, read_only=spec.read_only,
                               dynamic_typing=isinstance(spec.default, (float, tuple)))
    if spec.choices:
        desc.additional_constraints = 'one of: ' + ', '.join(spec.choices)
    if spec.low is not None and isinstance(spec.default, float):
        desc.floating_point_range = [FloatingPointRange(
            from_value=float(spec.low), to_value=float(spec.high), step=0.0)]
    elif spec.low is not None and isinstance(spec.default, int) \
            and not isinstance(spec.default, bool):
        desc.integer_range = [IntegerRange(from_value=int(spec.low), to_value=int(spec.high),
                                           step=1)]
    return desc


def declare_parameters(node: Node) -> NodeConfig:
    """
    Declare every parameter of :data:`PARAMS` on ``node`` and return the validated config.

    Raises
    ------
    ConfigError
        An override (params file, ``-p``) has the wrong type, is out of range or otherwise
        invalid; the message names the parameter.

    """
    declare_all(node)
    return config_from_values(current_values(node))


def declare_all(node: Node) -> None:
    """
    Declare every parameter of :data:`PARAMS` on ``node`` (no cross-parameter check).

    Raises
    ------
    ConfigError
        An override has the wrong type or is out of range; the message names the parameter.

    """
    for spec in PARAMS:
        try:
            default = list(spec.default) if isinstance(spec.default, tuple) else spec.default
            node.declare_parameter(spec.name, default, descriptor(spec))
        except ParameterException as err:
            raise ConfigError(f'parameter {spec.name}: {err}') from err


def current_values(node: Node) -> Dict[str, Any]:
    """
    Return the node's current value of every parameter of :data:`PARAMS`.

    Raises
    ------
    ConfigError
        A parameter was given without a value (``-p qos.depth:=``, ``depth:`` in a params
        file), which rclpy leaves uninitialised.

    """
    values = {}
    for spec in PARAMS:
        try:
            values[spec.name] = node.get_parameter(spec.name).value
        except ParameterUninitializedException as err:
            raise ConfigError(f'parameter {spec.name} was given no value') from err
    return values
