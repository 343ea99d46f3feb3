"""PoseEstimate: the fast constructor an estimator uses at every step is the dataclass's own."""

from __future__ import annotations

import copy
import dataclasses
import pickle

import numpy as np
import pytest

from slipenv.contracts import PoseEstimate

VALUES = (1.5, -2.0, 0.3, 0.8, -0.1, 0.02)


def test_construct_equals_the_dataclass_init() -> None:
    extras = {"k_sl": 900.0, "skipped": {}}
    built = PoseEstimate.construct(*VALUES, None, extras)
    init = PoseEstimate(*VALUES, None, {"k_sl": 900.0, "skipped": {}})
    assert built == init
    assert repr(built) == repr(init)
    assert vars(built) == vars(init)
    assert [f.name for f in dataclasses.fields(built)] == list(vars(built))
    assert built.extras is extras  # the estimator's dict, not a copy
    assert pickle.loads(pickle.dumps(built)) == init
    assert copy.deepcopy(built) == init
    assert dataclasses.replace(built, x_m=0.0) == PoseEstimate(0.0, *VALUES[1:], None, extras)


def test_construct_keeps_the_estimate_frozen_and_its_covariance() -> None:
    cov = np.diag([0.1, 0.2, 0.01])
    built = PoseEstimate.construct(*VALUES, cov, {})
    assert built.cov is cov
    with pytest.raises(dataclasses.FrozenInstanceError):
        built.x_m = 0.0  # type: ignore[misc]
    with pytest.raises(dataclasses.FrozenInstanceError):
        built.extras = {}  # type: ignore[misc]
