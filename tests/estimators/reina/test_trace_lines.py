"""FTrace's ground geometry: a rut wall's line fitted beside a diverging parallel edge."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from slipenv.estimators.reina.trace_lines import refine_angle
from slipenv.sensors.trace_camera import TraceCameraConfig

CONFIG = TraceCameraConfig()
CAMERA = CONFIG.nominal_camera()
XW, YW = CONFIG.wheel_xy_m


def edge_map(lines_m: list[tuple[float, float, float]]) -> np.ndarray:
    """A one-pixel edge map of ground lines (offset at the wheel [m], angle [rad], length [m])
    starting at the near edge of the view and running away from the wheel."""
    image = np.zeros(CAMERA.shape, np.uint8)
    x0 = XW - CONFIG.gap_m
    for offset, angle, length in lines_m:
        ends = np.array([[x0, YW + offset + (x0 - XW) * math.tan(angle)],
                         [x0 - length, YW + offset + (x0 - length - XW) * math.tan(angle)]])
        uv = np.round(CAMERA.ground_to_image(ends, CONFIG.ground_z_m)).astype(int)
        cv2.line(image, tuple(uv[0]), tuple(uv[1]), 255, 1)
    return image


def wall_line(offset: float, angle: float) -> np.ndarray:
    """(n_x, n_y, c) of a ground line through (x_w, y_w + offset) at ``angle``."""
    normal = np.array([-math.sin(angle), math.cos(angle)])
    return np.array([[*normal, float(normal @ [XW, YW + offset])]])


@pytest.mark.parametrize("wall_deg", [-3.0, 0.0, 2.0])
def test_wall_angle_is_not_pulled_by_a_diverging_edge_beside_it(wall_deg: float) -> None:
    # The watched rut's wall, and 5 mm beside it at the wheel an older rut's wall drifting 2°
    # away: the fit stays on the wall; a 12 mm band (the earlier setting) takes the other
    # edge's pixels for a third of the view and is pulled by about half the divergence.
    wall, other = math.radians(wall_deg), math.radians(wall_deg + 2.0)
    edges = edge_map([(0.04, wall, 0.58), (0.045, other, 0.58)])
    line = wall_line(0.04, wall)
    fitted = refine_angle(edges, CAMERA, CONFIG.ground_z_m, line, wall)
    assert math.degrees(fitted) == pytest.approx(wall_deg, abs=0.3)
    wide = refine_angle(edges, CAMERA, CONFIG.ground_z_m, line, wall, band_m=0.012)
    assert abs(math.degrees(wide) - wall_deg) > 0.6

