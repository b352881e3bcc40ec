"""Exception types of contact_detector.

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
