"""Feature core: paper eqs. 1-4, streamed per audio frame (no ROS imports)."""

from contact_detector.features.config import (EXTRA_FEATURES, FEATURE_SCHEMA_VERSION,
                                              FeatureConfig, PAPER_FEATURES)
from contact_detector.features.streaming import (FeatureFrames, StreamingFeatureExtractor,
                                                 TimeJumpError)

__all__ = ['EXTRA_FEATURES', 'FEATURE_SCHEMA_VERSION', 'FeatureConfig', 'FeatureFrames',
           'PAPER_FEATURES', 'StreamingFeatureExtractor', 'TimeJumpError']
