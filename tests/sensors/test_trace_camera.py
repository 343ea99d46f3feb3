"""The rear trace camera: geometry of the view, the truth it reports, the image it renders."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipenv.contracts.camera import PinholeCamera, downward_camera
from slipenv.sensors.trace_camera import TraceCamera, TraceCameraConfig
from slipenv.sensors.trace_history import ContactHistory, WheelTrack, history_from_poses

WHEELS = {"front_left": (0.30, 0.25), "rear_left": (-0.30, 0.25)}
CLEAN = TraceCameraConfig(p_old_trace=0.0, p_shadow=0.0, p_patch=0.0)


def crab(beta_rad: float, distance_m: float = 2.0, yaw_rad: float = 0.3) -> tuple:
    """Traces and final pose of a straight crab at slip angle ``beta_rad``."""
    s = np.linspace(0.0, distance_m, int(distance_m / 0.01) + 1)
    heading = yaw_rad + beta_rad
    poses = np.column_stack([s * math.cos(heading), s * math.sin(heading),
                             np.full_like(s, yaw_rad)])
    tracks = history_from_poses(poses, WHEELS, 0.08, 0.01)
    return tracks, [poses[-1, 0], poses[-1, 1], 0.0, 0.0, 0.0, yaw_rad]


def test_nadir_camera_covers_the_stated_footprint_and_round_trips() -> None:
    cam = downward_camera((-0.62, 0.25), 0.5, -0.09)
    corners = cam.ground_to_image([[-0.32, 0.65], [-0.92, -0.15]], -0.09)
    # Forward edge at the top row, left edge at the first column (image up = forward).
    np.testing.assert_allclose(corners, [[-0.5, -0.5], [319.5, 239.5]], atol=1e-9)
    uv = np.array([[10.0, 20.0], [300.0, 200.0], [160.0, 120.0]])
    back = cam.ground_to_image(cam.image_to_ground(uv, -0.09), -0.09)
    np.testing.assert_allclose(back, uv, atol=1e-9)


def test_tilted_camera_still_round_trips_through_the_ground() -> None:
    cam = downward_camera((-0.62, 0.25), 0.5, -0.09).with_tilt([0.01, -0.02, 0.015])
    xy = np.array([[-0.5, 0.3], [-0.8, 0.1]])
    np.testing.assert_allclose(cam.image_to_ground(cam.ground_to_image(xy, -0.09), -0.09), xy,
                               atol=1e-12)


@pytest.mark.parametrize("beta_deg", [-14.0, 0.0, 9.0])
def test_truth_angle_of_a_straight_crab_is_the_slip_angle(beta_deg: float) -> None:
    tracks, pose = crab(math.radians(beta_deg))
    frame = TraceCamera(CLEAN).measure(tracks, pose, np.random.default_rng(0))
    assert frame.trace_present
    assert frame.trace_angle_rad == pytest.approx(math.radians(beta_deg), abs=1e-9)
    assert frame.trace_offset_m == pytest.approx(0.0, abs=1e-9)


def test_image_is_seeded_grey_uint8_of_the_configured_shape() -> None:
    tracks, pose = crab(0.1)
    cam = TraceCamera(TraceCameraConfig(), calibration_rng=np.random.default_rng(3))
    a = cam.measure(tracks, pose, np.random.default_rng(7)).image
    b = cam.measure(tracks, pose, np.random.default_rng(7)).image
    c = cam.measure(tracks, pose, np.random.default_rng(8)).image
    assert a.dtype == np.uint8 and a.shape == (240, 320)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)


def test_rut_core_is_darker_than_the_sand_around_it() -> None:
    tracks, pose = crab(0.0, yaw_rad=0.0)
    cam = TraceCamera(CLEAN)
    image = cam.measure(tracks[1:], pose, np.random.default_rng(1)).image.astype(float)
    # Rear-left trace along body x at y = 0.25: the image column of the wheel-centre line.
    col = int(round(cam.camera.ground_to_image([[-0.6, 0.25]], -0.09)[0, 0]))
    core = image[:, col - 6: col + 7].mean()
    sand = np.r_[image[:, : col - 40].ravel(), image[:, col + 40:].ravel()].mean()
    assert core < sand - 15.0


def test_front_wheel_imprint_is_drawn_apart_when_the_rover_crabs() -> None:
    tracks, pose = crab(math.radians(12.0), yaw_rad=0.0)
    cam = TraceCamera(CLEAN)
    with_front = cam.measure(tracks, pose, np.random.default_rng(2))
    rear_only = cam.measure(tracks[1:], pose, np.random.default_rng(2))
    assert with_front.nuisances["second_imprint"] and not rear_only.nuisances["second_imprint"]
    # The front trace lies 0.6 m · tan 12° = 12.8 cm to the right at the contact point's x.
    uv = cam.camera.ground_to_image([[-0.34, 0.25 - 0.6 * math.tan(math.radians(12.0))]], -0.09)
    row, col = (int(round(v)) for v in uv[0, ::-1])
    diff = np.abs(with_front.image.astype(int) - rear_only.image.astype(int))
    assert diff[max(row - 3, 0): row + 4, col - 8: col + 9].mean() > 10.0


def test_no_history_means_no_trace() -> None:
    frame = TraceCamera(CLEAN).measure((), [0, 0, 0, 0, 0, 0], np.random.default_rng(0))
    assert not frame.trace_present and math.isnan(frame.trace_angle_rad)


def test_contact_history_thins_points_and_skips_wheels_in_the_air() -> None:
    hist = ContactHistory(["rear_left", "front_left"], [0.08, 0.08], min_spacing_m=0.01)
    for k in range(100):
        hist.append([[0.001 * k, 0.0, 0.0], [np.nan, 0.0, 0.0]], [0.01, 0.01])
    (track,) = hist.tracks()
    assert track.name == "rear_left" and len(track.points_m) == 10
    with pytest.raises(ValueError, match="contact_points_m"):
        hist.append([[0.0, 0.0, 0.0]], [0.0])


def test_camera_is_due_at_five_hertz() -> None:
    cam = TraceCamera(CLEAN)
    assert cam.due(0.0)
    cam.measure((), [0, 0, 0, 0, 0, 0], np.random.default_rng(0), t_s=0.0)
    assert not cam.due(0.1) and cam.due(0.2)


@pytest.mark.parametrize(("kwargs", "name"), [
    ({"pose": [0, 0, 0]}, "pose"),
    ({"pose": [0, 0, 0, 0, 0, np.nan]}, "pose"),
    ({"rng": 3}, "rng"),
    ({"history": [np.zeros((3, 3))]}, "history"),
])
def test_bad_inputs_name_the_argument(kwargs: dict, name: str) -> None:
    args = {"history": (), "pose": [0, 0, 0, 0, 0, 0], "rng": np.random.default_rng(0)}
    args.update(kwargs)
    with pytest.raises(ValueError, match=name):
        TraceCamera(CLEAN).measure(**args)


@pytest.mark.parametrize(("field", "value"), [("wheel_width_m", 0.0), ("p_shadow", 1.5),
                                              ("blur_sigma_px", (2.0, 1.0))])
def test_bad_config_names_the_field(field: str, value: object) -> None:
    with pytest.raises(ValueError, match=field):
        TraceCameraConfig(**{field: value})


def test_bad_camera_and_track_values_are_rejected() -> None:
    with pytest.raises(ValueError, match="fx_px"):
        PinholeCamera(320, 240, -1.0, 200.0, 160.0, 120.0, (0.0, 0.0, 0.5))
    with pytest.raises(ValueError, match="depth_m"):
        WheelTrack("rear_left", np.zeros((2, 3)), 0.08, np.array([0.01, -0.01]))
