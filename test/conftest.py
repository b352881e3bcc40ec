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

"""Test-session set-up: keep DDS on loopback with a domain of this run's own."""

import os

# Set before anything imports rclpy; inherited by every subprocess a test starts.
os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
os.environ['ROS_STATIC_PEERS'] = ''
os.environ.setdefault('ROS_DOMAIN_ID', str(10 + os.getpid() % 90))
# Under pytest-xdist (tools/test.sh runs two workers) each worker gets a domain of its own, so
# two node tests running at once never hear each other's topics. Once per worker: a pytest the
# worker starts (colcon test) inherits the domain and the marker. Fast DDS takes 0-232.
_worker = os.environ.get('PYTEST_XDIST_WORKER', '')
if _worker.startswith('gw') and os.environ.get('CONTACT_DETECTOR_TEST_WORKER') != _worker:
    os.environ['CONTACT_DETECTOR_TEST_WORKER'] = _worker
    os.environ['ROS_DOMAIN_ID'] = str(
        (int(os.environ['ROS_DOMAIN_ID']) + 100 + int(_worker[2:])) % 233)
os.environ.setdefault('MPLBACKEND', 'Agg')


import pytest  # noqa: E402  (after the environment above, before anything starts rclpy)


@pytest.fixture
def context():
    """Yield an rclpy context of the test's own, shut down after it."""
    import rclpy
    from rclpy.context import Context
    ctx = Context()
    rclpy.init(context=ctx)
    yield ctx
    rclpy.try_shutdown(context=ctx)


@pytest.fixture(scope='module')
def model(tmp_path_factory):
    """Return a model file for the module's node tests (the shipped one where it exists)."""
    import node_support
    return node_support.model_path(tmp_path_factory.mktemp('model'))
