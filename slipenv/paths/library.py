"""Named task paths: circles, straights, Lindgren's two test paths, field rows, S-curves.

Every builder validates its arguments and raises ``ValueError`` naming the bad one. Speeds that
the papers leave out are assumptions, marked as such.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from slipenv.contracts.names import lookup
from slipenv.paths import _validate as check
from slipenv.paths.builder import PathBuilder
from slipenv.paths.path import Path

LINDGREN_SPEED_MPS = 0.5  # [m/s] assumed: Lindgren does not state the vehicle's path speed


def circle(radius_m: float = 4.0, speed_mps: float = LINDGREN_SPEED_MPS, loops: float = 1.0,
           clockwise: bool = False, center: tuple[float, float] = (0.0, 0.0),
           start_heading_rad: float = 0.0) -> Path:
    """Circle of ``radius_m`` [m] about ``center`` [m], driven ``loops`` times at ``speed_mps``.

    The start point is where the tangent points along ``start_heading_rad`` [rad]; the length
    is 2 pi r loops and the curvature +1/r (counter-clockwise) or -1/r (clockwise).
    Yamauchi §3.1 uses r = 0.25 m at 0.05 m/s.
    """
    radius_m = check.positive("radius_m", radius_m)
    speed_mps = check.positive("speed_mps", speed_mps)
    loops = check.positive("loops", loops)
    cx, cy = check.point("center", center)
    heading = check.finite("start_heading_rad", start_heading_rad)
    side = -1.0 if clockwise else 1.0  # the centre lies on this side of the start heading
    x0 = cx + side * radius_m * math.sin(heading)
    y0 = cy - side * radius_m * math.cos(heading)
    builder = PathBuilder(x0, y0, heading, speed_mps)
    return builder.arc(radius_m, 2.0 * math.pi * loops, clockwise).build("circle")


def straight(length_m: float = 20.0, speed_mps: float = LINDGREN_SPEED_MPS,
             heading_rad: float = 0.0) -> Path:
    """Straight line of ``length_m`` [m] from the origin along ``heading_rad``."""
    speed_mps = check.positive("speed_mps", speed_mps)
    builder = PathBuilder(heading_rad=heading_rad, speed_mps=speed_mps)
    return builder.line(length_m).build("straight")


def lindgren_circles(radius_m: float = 4.0, speed_mps: float = LINDGREN_SPEED_MPS,
                     loops: float = 1.5) -> Path:
    """Lindgren's model-comparison path (Fig. 3, DESIGN §4): ``loops`` clockwise, then
    ``loops`` counter-clockwise, each of ``radius_m`` (4 m in the paper).

    With 1.5 loops the two circles touch at the joint, which the path passes three times:
    projecting with ``s_hint`` keeps the vehicle on its current branch.
    """
    radius_m = check.positive("radius_m", radius_m)
    speed_mps = check.positive("speed_mps", speed_mps)
    loops = check.positive("loops", loops)
    sweep = 2.0 * math.pi * loops
    builder = PathBuilder(speed_mps=speed_mps)
    builder.arc(radius_m, sweep, clockwise=True).arc(radius_m, sweep, clockwise=False)
    return builder.build("lindgren_circles")


def lindgren_straights(length_m: float = 10.0, n_legs: int = 4, turn_radius_m: float = 2.0,
                       speed_mps: float = LINDGREN_SPEED_MPS) -> Path:
    """Lindgren's laser-dropout path (Fig. 6-7): ``n_legs`` straights of ``length_m`` [m]
    joined by 180° arcs of ``turn_radius_m`` [m], alternately right and left.
    """
    length_m = check.positive("length_m", length_m)
    n_legs = check.count("n_legs", n_legs)
    turn_radius_m = check.positive("turn_radius_m", turn_radius_m)
    speed_mps = check.positive("speed_mps", speed_mps)
    builder = PathBuilder(speed_mps=speed_mps).line(length_m)
    for leg in range(1, n_legs):
        builder.arc(turn_radius_m, math.pi, clockwise=leg % 2 == 1).line(length_m)
    return builder.build("lindgren_straights")


def field_rows(row_length_m: float = 20.0, n_rows: int = 4, row_spacing_m: float = 3.0,
               speed_mps: float = 1.0, turn_speed_mps: float | None = None,
               headland_m: float | None = None, ramp_m: float = 2.0) -> Path:
    """A farm field: ``n_rows`` parallel rows joined by spline headland turns (boustrophedon).

    Parameters
    ----------
    row_length_m : float
        Length of each row [m].
    n_rows : int
        Number of rows (>= 1).
    row_spacing_m : float
        Distance between neighbouring rows [m]; rows stack to the left of the first one.
    speed_mps : float
        Speed along the rows [m/s].
    turn_speed_mps : float, optional
        Speed through the headland turns [m/s]; default ``speed_mps``. When it differs, the
        last and first ``ramp_m`` of each row change speed with constant acceleration.
    headland_m : float, optional
        How far each turn reaches beyond the row ends [m]; default ``row_spacing_m / 2``
        (peak curvature of each turn then sqrt(2) / headland_m).
    ramp_m : float
        Length of the speed ramps [m]; 2 ramps must fit in a row.
    """
    row_length_m = check.positive("row_length_m", row_length_m)
    n_rows = check.count("n_rows", n_rows)
    row_spacing_m = check.positive("row_spacing_m", row_spacing_m)
    speed_mps = check.positive("speed_mps", speed_mps)
    v_turn = (speed_mps if turn_speed_mps is None
              else check.positive("turn_speed_mps", turn_speed_mps))
    depth = (0.5 * row_spacing_m if headland_m is None
             else check.positive("headland_m", headland_m))
    ramp_m = check.positive("ramp_m", ramp_m)
    if v_turn != speed_mps and 2.0 * ramp_m >= row_length_m:
        raise ValueError(f"ramp_m={ramp_m} leaves no constant-speed part of a "
                         f"{row_length_m} m row")
    builder = PathBuilder(speed_mps=speed_mps)
    for row in range(n_rows):
        ramp_in = row > 0 and v_turn != speed_mps
        ramp_out = row < n_rows - 1 and v_turn != speed_mps
        if ramp_in:
            builder.line(ramp_m, speed_mps)
        builder.line(row_length_m - ramp_m * (ramp_in + ramp_out))
        if ramp_out:
            builder.line(ramp_m, v_turn)
        if row < n_rows - 1:
            builder.u_turn(row_spacing_m, depth, left=row % 2 == 0)
    return builder.build("field_rows")


def s_curve(length_m: float = 10.0, offset_m: float = 2.0, speed_mps: float = 1.0,
            lead_m: float = 2.0) -> Path:
    """Lane change: ``lead_m`` straight, an S of two quadratic splines moving ``offset_m`` [m]
    left (< 0: right) over ``length_m`` [m], and ``lead_m`` straight again.
    """
    length_m = check.positive("length_m", length_m)
    offset_m = check.finite("offset_m", offset_m)
    speed_mps = check.positive("speed_mps", speed_mps)
    lead_m = check.positive("lead_m", lead_m)
    builder = PathBuilder(speed_mps=speed_mps).line(lead_m)
    return builder.s_bend(length_m, offset_m).line(lead_m).build("s_curve")


def slalom(n_gates: int = 4, gate_spacing_m: float = 5.0, amplitude_m: float = 1.0,
           speed_mps: float = 1.0) -> Path:
    """Slalom through ``n_gates`` gates ``gate_spacing_m`` [m] apart, alternately
    ``amplitude_m`` [m] left and right of the x axis, passing each gate parallel to x.
    Between gates the path is an S of two quadratic splines; a straight of one gate spacing
    follows the last gate.
    """
    n_gates = check.count("n_gates", n_gates)
    gate_spacing_m = check.positive("gate_spacing_m", gate_spacing_m)
    amplitude_m = check.positive("amplitude_m", amplitude_m)
    speed_mps = check.positive("speed_mps", speed_mps)
    builder = PathBuilder(speed_mps=speed_mps)
    y = 0.0
    for gate in range(n_gates):
        target = amplitude_m if gate % 2 == 0 else -amplitude_m
        builder.s_bend(gate_spacing_m, target - y)
        y = target
    return builder.line(gate_spacing_m).build("slalom")


PATHS: dict[str, Callable[..., Path]] = {
    "circle": circle,
    "straight": straight,
    "lindgren_circles": lindgren_circles,
    "lindgren_straights": lindgren_straights,
    "field_rows": field_rows,
    "s_curve": s_curve,
    "slalom": slalom,
}


def path_by_name(name: str, **kw: object) -> Path:
    """Build the registered path ``name`` with keyword arguments ``kw``.

    Raises
    ------
    ValueError
        If ``name`` is unknown (the message lists the known names).
    """
    return lookup(PATHS, name, "path")(**kw)
