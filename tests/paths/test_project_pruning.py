"""``Path.project`` skips segments by their bounding boxes without changing one bit.

A segment whose box lies farther from the query than the best point found so far cannot
replace it, so the projection skips it. The reference below is the search without boxes (every
segment in the window asked for its nearest point, ties to the smallest ``s``); the projection
must return exactly its answer on every registered env's path and on every library path, for
queries on, near and far from the path, with and without a hint.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipenv.envs.registration import PRESETS, preset_config
from slipenv.paths import PATHS, Arc, Line, Path, PathProjection, QuadraticSpline, path_by_name
from slipenv.paths.segments import Nearest


def _reference_project(path: Path, x: float, y: float, s_hint: float | None) -> PathProjection:
    """The projection as it was before the boxes: every segment of the window searched."""
    if s_hint is None:
        lo, hi = 0.0, path.length_m
    else:
        s_hint = min(max(float(s_hint), 0.0), path.length_m)
        lo = max(s_hint - path.search_back_m, 0.0)
        hi = min(s_hint + path.search_ahead_m, path.length_m)
    starts = [0.0]
    for seg in path.segments:
        starts.append(starts[-1] + seg.length_m)
    best: Nearest | None = None
    best_i = -1
    for i, seg in enumerate(path.segments):
        if starts[i + 1] < lo or starts[i] > hi:
            continue
        near = seg.nearest(x, y, max(lo - starts[i], 0.0), min(hi - starts[i], seg.length_m))
        if best is None or near.d2 < best.d2 - 1e-12:
            best, best_i = near, i
    assert best is not None
    s = starts[best_i] + best.s
    cross = (y - best.y) * best.tx - (x - best.x) * best.ty
    return PathProjection(s, cross, math.atan2(best.ty, best.tx), best.kappa,
                          path.segments[best_i].speed(best.s), path.length_m - s)


def _paths() -> dict[str, Path]:
    out = {f"env {env_id}": _env_path(env_id) for env_id in sorted(PRESETS)}
    out.update({f"library {name}": path_by_name(name) for name in sorted(PATHS)})
    return out


def _env_path(env_id: str) -> Path:
    cfg = preset_config(env_id)
    return cfg.path if isinstance(cfg.path, Path) else path_by_name(cfg.path, **cfg.path_kwargs)


PATH_CASES = _paths()


@pytest.mark.parametrize("name", sorted(PATH_CASES))
def test_projection_with_boxes_is_the_full_search_bit_for_bit(name):
    path = PATH_CASES[name]
    rng = np.random.default_rng(abs(hash(name)) % 2**32)
    s = rng.uniform(0.0, path.length_m, 300)
    offsets = np.concatenate([np.zeros(20), rng.normal(0.0, 0.05, 180), rng.normal(0.0, 1.0, 80),
                              rng.uniform(-10.0, 10.0, 20)])
    skipped = 0
    for sk, off, jitter in zip(s, offsets, rng.normal(0.0, 0.3, 300), strict=True):
        x0, y0, heading = path.pose_at(float(sk))
        x, y = x0 - off * math.sin(heading), y0 + off * math.cos(heading)
        for hint in (None, float(sk) + jitter, float(sk)):
            got = path.project(x, y, s_hint=hint)
            assert got == _reference_project(path, x, y, hint), (name, x, y, hint)
        skipped += len(path.segments) > 1
    assert skipped > 0 or len(path.segments) == 1


def test_every_segment_lies_inside_its_box():
    segments = [
        Line((1.0, -2.0), (-3.0, 4.0), 1.0, 1.0),
        Arc((0.5, 0.5), 2.0, 0.3, 5.0, True, 1.0, 1.0),
        QuadraticSpline((0.0, 0.0), (2.0, 3.0), (4.0, -1.0), 1.0, 1.0),
        QuadraticSpline((0.0, 0.0), (-1.0, 0.5), (1.0, 1.0), 1.0, 1.0),
    ]
    for seg in segments:
        x_min, y_min, x_max, y_max = seg.bounds()
        for s in np.linspace(0.0, seg.length_m, 401):
            x, y = seg.point(float(s))
            assert x_min - 1e-12 <= x <= x_max + 1e-12 and y_min - 1e-12 <= y <= y_max + 1e-12


def test_boxes_skip_far_segments_of_a_long_path():
    # 20 short lines in a row, a window from 0.5 m behind to 5 m ahead of the hint: a query
    # beside the 6th line needs the window's first line (the search starts with it) and its
    # own, not the 5 lines further ahead
    segs = [Line((float(i), 0.0), (float(i + 1), 0.0), 1.0, 1.0) for i in range(20)]
    path = Path(segs, search_back_m=0.5, search_ahead_m=5.0)
    asked = []
    for seg in segs:
        original = seg.nearest

        def spy(x, y, s_lo, s_hi, _seg=seg, _original=original):
            asked.append(_seg)
            return _original(x, y, s_lo, s_hi)

        object.__setattr__(seg, "nearest", spy)
    proj = path.project(5.2, 0.1, s_hint=5.2)
    assert proj.s == pytest.approx(5.2)
    assert asked == [segs[4], segs[5]]
