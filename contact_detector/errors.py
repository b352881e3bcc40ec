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
Exception types of contact_detector.

Every error the package raises on purpose derives from :class:`ContactDetectorError`, so callers
can catch the project's errors without catching programming errors.
"""


class ContactDetectorError(Exception):
    """Base class of every error raised on purpose by contact_detector."""


class ConfigError(ContactDetectorError, ValueError):
    """A configuration or parameter value is invalid."""


class InputError(ContactDetectorError, ValueError):
    """Input data is malformed (NaN/Inf, wrong shape, stamps out of order, ...)."""


class ModelError(ContactDetectorError):
    """A model file is missing, corrupt, or does not match the running feature contract."""


class BagError(ContactDetectorError):
    """A rosbag cannot be read or lacks the topics a tool needs."""
