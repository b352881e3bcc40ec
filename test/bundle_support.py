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

"""A toy model for detector tests: a small forest fitted on a rule over named feature columns."""

from contact_detector.features.config import FEATURE_SCHEMA_VERSION, FeatureConfig
from contact_detector.model.bundle import ModelBundle, runtime_versions
from contact_detector.model.rule import DecisionRule
import numpy as np
from sklearn.ensemble import RandomForestClassifier


def toy_bundle(*, config: FeatureConfig, x: np.ndarray, y: np.ndarray,
               created: str) -> ModelBundle:
    """
    Fit 5 trees on ``x`` (n, config.n_features) and labels ``y`` (n,); release at p >= 0.6 x2.

    The tests choose ``x`` and ``y`` so that the forest encodes a known rule (for example
    "contact when force_shift_min > 1 N"), so what the detector does follows from the features.
    """
    forest = RandomForestClassifier(n_estimators=5, random_state=0).fit(x, y)
    return ModelBundle(forest=forest, feature_config=config, feature_names=config.feature_names,
                       feature_schema_version=FEATURE_SCHEMA_VERSION,
                       label_window={'start_s': 0.0, 'end_s': 0.3},
                       decision_rule=DecisionRule(threshold=0.6, confirm_frames=2,
                                                  refractory_s=0.5),
                       versions=runtime_versions(), training={}, metrics={}, created=created)


def lasting_change_bundle(*, config: FeatureConfig, n: int, created: str) -> ModelBundle:
    """
    Return a :func:`toy_bundle` that says contact when ``force_shift_min > 1`` N.

    ``n`` random frames, every feature ``|N(0, 1)|`` but ``force_shift_min`` uniform in [0, 3]
    N: the forest encodes "a lasting change of the load", whatever the other columns say.
    """
    rng = np.random.default_rng(0)
    x = np.abs(rng.normal(size=(n, config.n_features)))
    lasting = config.feature_names.index('force_shift_min')
    x[:, lasting] = rng.uniform(0, 3, size=n)
    y = (x[:, lasting] > 1.0).astype(int)
    return toy_bundle(config=config, x=x, y=y, created=created)


def unloading_bundle(*, config: FeatureConfig, created: str) -> ModelBundle:
    """
    Return a :func:`toy_bundle` that says contact when a lasting change unloads the hand.

    4000 random frames: ``force_shift_min`` uniform in [0, 3] N, ``force_carried_cos`` in
    [-1, 1], the rest ``|N(0, 1)|``; contact when ``force_shift_min > 1`` N and
    ``force_carried_cos < -0.5``. The table taking weight off releases; a push across the
    carried load does not, nor does any change on a sensor whose carried load is wrong.
    """
    rng = np.random.default_rng(0)
    x = np.abs(rng.normal(size=(4000, config.n_features)))
    lasting = config.feature_names.index('force_shift_min')
    cos = config.feature_names.index('force_carried_cos')
    x[:, lasting] = rng.uniform(0, 3, size=4000)
    x[:, cos] = rng.uniform(-1, 1, size=4000)
    y = ((x[:, lasting] > 1.0) & (x[:, cos] < -0.5)).astype(int)
    return toy_bundle(config=config, x=x, y=y, created=created)
