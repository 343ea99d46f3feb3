"""Task geometry: path segments, paths, projection and named paths (pure numpy, no PyBullet).

Segments follow Lindgren §2.3 (straight lines, circular arcs, quadratic splines, each with a
constant-acceleration speed profile); :meth:`Path.project` gives the path-relative errors the
controllers use every step.
"""

from slipenv.paths.builder import PathBuilder
from slipenv.paths.library import (
    PATHS,
    circle,
    field_rows,
    lindgren_circles,
    lindgren_straights,
    path_by_name,
    s_curve,
    slalom,
    straight,
)
from slipenv.paths.path import (
    CONTINUITY_TOL_M,
    CONTINUITY_TOL_MPS,
    CONTINUITY_TOL_RAD,
    Path,
    PathProjection,
    PathSamples,
    sample_path,
)
from slipenv.paths.segments import Arc, Line, Segment
from slipenv.paths.spline import QuadraticSpline

__all__ = [
    "CONTINUITY_TOL_M",
    "CONTINUITY_TOL_MPS",
    "CONTINUITY_TOL_RAD",
    "PATHS",
    "Arc",
    "Line",
    "Path",
    "PathBuilder",
    "PathProjection",
    "PathSamples",
    "QuadraticSpline",
    "Segment",
    "circle",
    "field_rows",
    "lindgren_circles",
    "lindgren_straights",
    "path_by_name",
    "s_curve",
    "sample_path",
    "slalom",
    "straight",
]
