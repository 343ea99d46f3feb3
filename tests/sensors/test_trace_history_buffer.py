"""The contact history keeps the newest points at the minimum spacing, whatever its storage.

``ContactHistory`` keeps one buffer per wheel, not lists of small arrays; its tracks must be
exactly those of the plain rule: a point is kept when it is finite and at least
``min_spacing_m`` from the wheel's last kept point, and only the newest ``max_points`` stay.
"""

from __future__ import annotations

import numpy as np

from slipenv.sensors.trace_history import ContactHistory


def _plain_rule(samples, sinks, spacing, max_points):
    """The history's rule written out with lists, per wheel: (points, depths)."""
    kept = [([], []) for _ in range(samples.shape[1])]
    for pts, sink in zip(samples, sinks, strict=True):
        for i, (pts_i, dep_i) in enumerate(kept):
            if not (np.all(np.isfinite(pts[i])) and np.isfinite(sink[i])):
                continue
            if pts_i and np.hypot(*(pts[i, :2] - pts_i[-1][:2])) < spacing:
                continue
            pts_i.append(pts[i].copy())
            dep_i.append(max(float(sink[i]), 0.0))
            del pts_i[:-max_points], dep_i[:-max_points]
    return kept


def test_tracks_follow_the_spacing_and_length_rule_through_buffer_wraps():
    rng = np.random.default_rng(3)
    n_wheels, spacing, max_points = 3, 0.01, 7
    steps = rng.normal(0.0, 0.006, (200, n_wheels, 3))
    samples = np.cumsum(steps, axis=0)
    samples[rng.random((200, n_wheels)) < 0.05] = np.nan  # wheels in the air
    sinks = rng.normal(0.01, 0.01, (200, n_wheels))  # some negative: stored as 0
    history = ContactHistory(["a", "b", "c"], [0.1, 0.2, 0.3], spacing, max_points)
    for k, (pts, sink) in enumerate(zip(samples, sinks, strict=True)):
        history.append(pts, sink)
        if k % 13 == 0 or k == len(samples) - 1:
            expected = _plain_rule(samples[:k + 1], sinks[:k + 1], spacing, max_points)
            tracks = {tr.name: tr for tr in history.tracks()}
            for name, (pts_i, dep_i) in zip("abc", expected, strict=True):
                if len(pts_i) < 2:
                    assert name not in tracks
                    continue
                np.testing.assert_array_equal(tracks[name].points_m, np.array(pts_i))
                np.testing.assert_array_equal(tracks[name].depth_m, np.array(dep_i))
    assert max(len(tr.points_m) for tr in history.tracks()) == max_points


def test_tracks_are_copies_and_clear_forgets_everything():
    history = ContactHistory(["a"], [0.1], 0.01, 3)
    for x in (0.0, 0.02, 0.04):
        history.append([[x, 0.0, 0.0]], [0.01])
    (track,) = history.tracks()
    for x in (0.06, 0.08, 0.10, 0.12):
        history.append([[x, 0.0, 0.0]], [0.02])
    np.testing.assert_array_equal(track.points_m[:, 0], [0.0, 0.02, 0.04])  # unchanged
    history.clear()
    assert history.tracks() == ()
    history.append([[5.0, 0.0, 0.0]], [0.01])
    history.append([[5.005, 0.0, 0.0]], [0.01])  # too close to the first after the clear
    assert history.tracks() == ()
