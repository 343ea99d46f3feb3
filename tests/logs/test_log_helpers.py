"""Helpers the diagnosis uses: ground-truth mask, wheel angles and speeds, slices, segments."""

from __future__ import annotations

import numpy as np
import pytest

from slipenv.logs import Log, LogMeta, read_log, write_log


def test_ground_truth_missing_in_stretches_is_accepted_and_masked(small_log, tmp_path):
    back = read_log(write_log(small_log, tmp_path / "log"))
    expected = ~((back.t > 0.25) & (back.t < 0.55))  # the synthetic gap: samples 3, 4, 5
    np.testing.assert_array_equal(back.gt_mask, expected)
    assert back.gt_mask.sum() == 7
    assert np.isnan(back.ground_truth()[3:6]).all()


def test_mask_needs_all_three_ground_truth_values(small_log):
    small_log.signals["gt_yaw"][8] = np.nan  # position without heading at one sample
    assert not small_log.gt_mask[8]
    assert small_log.gt_mask[9]


def test_wheel_angle_is_counts_over_counts_per_rad(small_log):
    np.testing.assert_allclose(small_log.wheel_angle("right"),
                               small_log.signals["enc_right"] / 100.0)
    angles = small_log.wheel_angles()
    assert angles.shape == (10, 2)
    np.testing.assert_allclose(angles[-1], [0.9, 1.8])  # 1 and 2 rad/s for 0.9 s


def test_wheel_speeds_by_differencing_recover_constant_rates(small_log):
    speeds = small_log.wheel_speeds()
    assert np.isnan(speeds[0]).all()
    np.testing.assert_allclose(speeds[1:], np.tile([1.0, 2.0], (9, 1)), atol=1e-9)


def test_slice_is_closed_and_keeps_counts_cumulative(small_log):
    part = small_log.slice(0.2, 0.6)
    np.testing.assert_allclose(part.t, [0.2, 0.3, 0.4, 0.5, 0.6])
    assert part.signals["enc_left"][0] == 20.0
    assert part.columns == small_log.columns
    assert part.meta.data == small_log.meta.data


def _gappy_log() -> Log:
    """10 s at 10 Hz with ground truth missing for 2.5 s < t < 6 s."""
    t = np.arange(101) * 0.1
    gt = np.where((t > 2.5) & (t < 6.0), np.nan, 0.0)
    meta = LogMeta.new("skid_steer", ["left", "right"], 0.1, 0.5, 10.0)
    return Log.from_arrays(meta, t=t, enc_left=np.arange(101), enc_right=np.arange(101),
                           gt_x=gt, gt_y=gt, gt_yaw=gt)


def test_segmentation_skips_stretches_without_ground_truth():
    log = _gappy_log()
    bounds = log.segment_bounds(1.0)
    starts = [round(float(log.t[a]), 6) for a, _ in bounds]
    assert starts == [0.0, 1.0, 2.0, 6.0, 7.0, 8.0, 9.0]
    for a, b in bounds:
        assert log.gt_mask[a]
        assert log.t[b - 1] - log.t[a] == pytest.approx(1.0)


def test_segments_are_logs_of_the_requested_duration():
    segments = _gappy_log().segments(2.5)
    # 0-2.5, 2.5-5 (starts on the last truth before the gap), 6-8.5; 8.5-11 is too short
    assert [len(s) for s in segments] == [26, 26, 26]
    assert [s.t[0] for s in segments] == pytest.approx([0.0, 2.5, 6.0])
    assert all(s.gt_mask[0] for s in segments)


def test_segment_duration_must_be_positive(small_log):
    with pytest.raises(ValueError, match="duration_s"):
        small_log.segment_bounds(0.0)
