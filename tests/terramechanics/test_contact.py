"""Slip convention and contact geometry."""

import math

import numpy as np
import pytest

from slipenv.terramechanics import ContactGeometry, slip_ratio


@pytest.mark.parametrize(("rim", "ground", "expected"), [
    (1.0, 0.9, 0.1),     # drive: 1 - v/(r omega)
    (0.9, 1.0, -0.1),    # braking: (r omega - v)/|v|
    (1.0, 0.0, 1.0),     # spinning in place
    (0.0, 1.0, -1.0),    # locked wheel sliding forward
    (-1.0, -0.9, -0.1),  # reverse drive pushes backwards
    (1.0, 1.0, 0.0),     # free rolling
    (0.0, 0.0, 0.0),     # standing still: no 0/0
    (1.0, -0.5, 1.0),    # driving forward while sliding back: clipped to full slip
    (-0.5, 1.0, -1.0),   # turning backwards while moving forward
])
def test_slip_ratio_follows_the_documented_convention(rim, ground, expected):
    assert slip_ratio(rim, ground) == pytest.approx(expected, rel=1e-14, abs=1e-15)


def test_slip_ratio_is_vectorised_and_bounded():
    rng = np.random.default_rng(0)
    rim, ground = rng.normal(size=(2, 1000))
    s = slip_ratio(rim, ground)
    assert s.shape == (1000,) and np.all(np.abs(s) <= 1.0)
    drive = (rim > ground) & (ground >= 0.0)
    assert s[drive] == pytest.approx(1.0 - ground[drive] / rim[drive], rel=1e-12)


def test_wheel_geometry_properties():
    g = ContactGeometry(radius_m=0.092, width_m=0.11, contact_length_m=0.06)
    assert not g.is_track
    assert g.area_m2 == pytest.approx(0.0066, rel=1e-14)
    assert g.shear_length_m == 0.06 and g.rut_share == 1.0


def test_track_segment_geometry_properties():
    g = ContactGeometry(radius_m=0.05, width_m=0.11, contact_length_m=0.15, track_length_m=0.6)
    assert g.is_track
    assert g.shear_length_m == 0.6 and g.rut_share == 0.25


@pytest.mark.parametrize(("key", "bad"), [("radius_m", 0.0), ("width_m", -0.1),
                                          ("contact_length_m", math.nan),
                                          ("track_length_m", math.inf)])
def test_invalid_length_raises_naming_field_and_value(key, bad):
    kwargs = {"radius_m": 0.1, "width_m": 0.1, "contact_length_m": 0.05, key: bad}
    with pytest.raises(ValueError, match=rf"{key}={bad!r}"):
        ContactGeometry(**kwargs)


def test_track_shorter_than_its_segment_raises():
    with pytest.raises(ValueError, match="track_length_m=0.1 must be >= contact_length_m=0.2"):
        ContactGeometry(radius_m=0.1, width_m=0.1, contact_length_m=0.2, track_length_m=0.1)
