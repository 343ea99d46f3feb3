"""Every vehicle kind is diagnosed (rover4ws included; torque slip on
skid-steer and rover logs), and soil that varies in space is mapped as regions with
continuous edges (unions of rectangles) that the simulation takes as a ``PatchSoilMap``.
Logs from the kinematic generator."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from slipenv.diagnose import regions, synth
from slipenv.diagnose.cli import diagnose
from slipenv.diagnose.effects import effect
from slipenv.diagnose.extension import apply_model
from slipenv.diagnose.fit import Problem, fit
from slipenv.diagnose.kinematic import KinematicTruth, SoilDisc, SoilRegion, kinematic_log
from slipenv.diagnose.replay import build_segments, simulate
from slipenv.diagnose.select import cross_validate, make_folds
from slipenv.envs.factory import make_soil_map
from slipenv.terramechanics.soil_map import Circle, PatchSoilMap

Z_LIMIT = 3.0


def _quiet(fn, *args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fn(*args, **kwargs)


def test_nominal_rover_replay_follows_a_clean_rover_log():
    # the double-Ackermann replay of the logged wheel angles and steering reproduces the pose
    log = kinematic_log(1, None, kind="rover4ws", duration_s=30.0, slip_sigma=0.0)
    seg = build_segments([log], segment_s=10.0)
    pred = simulate(seg, {})
    err = np.hypot(*(pred[..., :2] - seg.gt[..., :2])[seg.gt_ok].T)
    travel = 0.5 * 10.0  # [m] 0.5 m/s over a segment
    assert np.max(err) < 0.002 * travel + 0.005  # encoder quantisation and 1 mm truth noise


def test_a_rover_log_is_diagnosed_and_its_radius_error_named():
    truth = KinematicTruth(0.1, 0.1015, 0.5)  # right wheels 1.5 % larger
    report, _ = _quiet(diagnose, [kinematic_log(7, truth, kind="rover4ws", duration_s=90.0)],
                       "<rover>")
    assert report["vehicle_kind"] == "rover4ws"
    assert report["cause"] == "rolling_radius", report["candidates"]
    for wheel, true in (("front_right", 0.1015), ("rear_right", 0.1015),
                        ("front_left", 0.1), ("rear_left", 0.1)):
        value, se = report["parameters"][f"radius_{wheel}_m"]
        assert abs(value - true) <= Z_LIMIT * se + 2e-4 * true, (wheel, value, se)


def test_a_clean_rover_log_gives_none():
    report, _ = _quiet(diagnose, [kinematic_log(8, None, kind="rover4ws", duration_s=90.0)],
                       "<rover>")
    assert report["cause"] == "none" and report["also"] == [], report["candidates"]


@pytest.mark.parametrize("kind", ["skid_steer", "rover4ws"])
def test_torque_slip_is_fitted_and_predicts_held_out_segments_on_every_kind(kind):
    c_true = 0.006  # [1/(N m)]: 3 % slip at the generator's 5 N m
    log = kinematic_log(9, None, kind=kind, duration_s=60.0, torque_slip_per_nm=c_true)
    problem = Problem.from_segments(build_segments([log]))
    assert effect("torque_slip").applicable(problem.seg) is None
    folds = make_folds(problem.seg)
    base = _quiet(cross_validate, problem, (), folds)
    cand = _quiet(cross_validate, problem, ("torque_slip",), folds)
    assert cand.errors.sum() < 0.2 * base.errors.sum()
    f = _quiet(fit, problem, ("torque_slip",))
    for name, value in f.params["torque_slip"].__dict__.items():
        se = f.se["torque_slip"][name]
        assert abs(value - c_true) <= Z_LIMIT * se + 0.02 * c_true, (name, value, se)


def test_turning_slip_stays_a_skid_steer_effect():
    seg = build_segments([kinematic_log(2, None, kind="rover4ws", duration_s=30.0)])
    assert effect("turning_slip").applicable(seg) is not None


# Two rectangles of softer soil, not aligned with any grid, in an 8 m field swept lane by lane.
REGIONS = (SoilRegion(-4.0, -4.0, -0.5, 0.0, 0.008), SoilRegion(1.0, 0.5, 4.0, 4.0, 0.006))


def _field_log():
    return kinematic_log(3, None, duration_s=180.0, route="field", soil_regions=REGIONS)


@pytest.fixture(scope="module")
def field_problem():
    return Problem.from_segments(build_segments([_field_log()]))


@pytest.fixture(scope="module")
def field_map(field_problem):
    """The soil map fitted on every segment of the field log."""
    return _quiet(fit, field_problem, ("soil_map",))


@pytest.fixture(scope="module")
def field_diagnosis():
    """The field log's diagnosis: (log, report, selection, problem). The selection holds the
    held-out errors of the nominal model and of every effect, each refitted with one fold left
    out (``cross_validate`` on ``make_folds``), so a test of them need not refit them."""
    log = _field_log()
    report, (sel, problem) = _quiet(diagnose, [log], "<field>")
    return log, report, sel, problem


def _truth_compliance(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    c = np.zeros(np.broadcast(x, y).shape)
    for region in REGIONS:
        c = c + np.where(region.contains(x, y), region.compliance_per_nm, 0.0)
    return c


def test_soil_regions_are_mapped_and_the_map_cuts_the_held_out_error(field_diagnosis,
                                                                      field_map):
    _, _, sel, problem = field_diagnosis
    np.testing.assert_array_equal(sel.folds, make_folds(problem.seg))
    base = sel.baseline["pose"]
    single, mapped = (next(c for c in sel.candidates if c.effects == (name,))
                      for name in ("torque_slip", "soil_map"))
    assert base.effects == () and len(base.errors) == len(problem.seg)
    ratio = mapped.errors.sum() / base.errors.sum()
    assert ratio < 0.2, ratio  # the map predicts segments it never saw (0.08 measured)
    assert mapped.errors.sum() < 0.3 * single.errors.sum()  # one stiffness everywhere cannot
    # the parameter count is what the folds' maps use (angle, count, each shape's corners,
    # region and kind, each region's compliance), not every shape the contract could hold
    used = [2 + 6 * len(f.params["soil_map"].layout().rects) + f.params["soil_map"].regions
            for f in mapped.fold_fits]
    assert mapped.n_params == max(used) < 35 and single.n_params == 2
    m = field_map.params["soil_map"]
    assert m.regions >= 2
    # where the route went, the map's stiffness matches the truth's soft/firm split
    pos = problem.seg.pos[np.abs(problem.seg.dphi).sum(axis=-1) > 0]
    fitted, true = m.compliance_at(pos), _truth_compliance(pos[:, 0], pos[:, 1])
    soft = true > 0
    agree = np.mean((fitted > 0.5 * REGIONS[1].compliance_per_nm) == soft)
    assert agree > 0.95, agree
    for level in (0.006, 0.008):  # each soft region's compliance within 5 % (0.5 % measured):
        near = np.isclose(true, level)  # the regions' edges follow the fields' edges
        assert abs(np.median(fitted[near]) - level) < 0.05 * level


def test_a_field_log_is_named_soil_map_and_its_report_shows_where_the_ground_is_soft(
        field_diagnosis, tmp_path):
    from slipenv.diagnose.report import write_human_report

    log, report, sel, problem = field_diagnosis
    assert report["cause"] == "soil_map", report["candidates"]
    folder = write_human_report(tmp_path / "rep", report, sel, problem, logs=[log])
    assert (folder / "soil.png").stat().st_size > 10_000
    text = (folder / "report.md").read_text()
    assert "soil map: " in text and "map_rect" not in text


def test_the_generators_turned_fields_and_discs_hold_the_points_they_should():
    x, y = np.random.default_rng(2).uniform(-4.0, 4.0, (2, 2000))
    # a 4 x 2 m field turned a quarter turn about its centre (1, 0) is 2 x 4 m
    turned = SoilRegion(-1.0, -1.0, 3.0, 1.0, 0.005, angle_rad=np.pi / 2)
    upright = SoilRegion(0.0, -2.0, 2.0, 2.0, 0.005)
    assert np.array_equal(turned.contains(x, y), upright.contains(x, y))
    disc = SoilDisc(1.0, -1.0, 1.5, 0.005)
    assert np.array_equal(disc.contains(x, y), np.hypot(x - 1.0, y + 1.0) < 1.5)
    with pytest.raises(ValueError, match="radius_m > 0"):
        SoilDisc(0.0, 0.0, 0.0, 0.005)


def test_a_hand_written_map_of_one_rectangle_applies_and_a_bad_one_is_named():
    one = {"map_angle_rad": [0.3, 0.0], "map_rects": [1.0, 0.0], "map_rect0_u0_m": [0.0, 0.0],
           "map_rect0_v0_m": [-1.0, 0.0], "map_rect0_u1_m": [2.0, 0.0],
           "map_rect0_v1_m": [1.0, 0.0], "map_rect0_region": [0.0, 0.0],
           "c_region0_per_nm": [0.01, 0.0]}
    config = synth.base_config("diff_drive")
    report = {"format": "slipenv-diagnosis/1", "cause": "soil_map", "also": [],
              "parameters": one}
    assert isinstance(apply_model(config, report).soil_map, PatchSoilMap)
    two = {**one, "map_rects": [2.0, 0.0]}  # a second rectangle promised, none given
    with pytest.raises(ValueError, match="rectangle 1 needs u1_m > u0_m"):
        apply_model(config, {**report, "parameters": two})
    # a disc is the one inscribed in a square: this 2 x 2 m one applies, a 2 x 1 m one and
    # a shape of no known kind are named
    round_one = {**one, "map_rect0_shape": [1.0, 0.0]}
    extended = apply_model(config, {**report, "parameters": round_one}).soil_map
    assert isinstance(extended, PatchSoilMap)
    assert isinstance(extended.patches[0][0], Circle)
    flat = {**round_one, "map_rect0_v1_m": [0.0, 0.0]}
    with pytest.raises(ValueError, match="disc 0 needs a square"):
        apply_model(config, {**report, "parameters": flat})
    with pytest.raises(ValueError, match="rect0_shape must be 0"):
        apply_model(config, {**report, "parameters": {**one, "map_rect0_shape": [2.0, 0.0]}})


TURNED = (SoilRegion(-3.5, -3.0, -0.5, -0.5, 0.008, angle_rad=0.52),  # fields 30 deg to
          SoilRegion(0.5, 0.5, 3.5, 3.0, 0.006, angle_rad=0.52))  # the lanes
DISC_AND_L = (SoilDisc(-1.5, 1.5, 1.8, 0.008),  # a disc, and an L-shaped field of one soil
              SoilRegion(0.5, -3.5, 3.5, -1.5, 0.006), SoilRegion(2.0, -1.5, 3.5, 1.0, 0.006))


@pytest.mark.parametrize("layout", [TURNED, DISC_AND_L], ids=["turned", "disc_and_l"])
def test_soil_regions_of_other_shapes_are_mapped(layout):
    log = kinematic_log(3, None, duration_s=180.0, route="field", soil_regions=layout)
    problem = Problem.from_segments(build_segments([log]))
    folds = make_folds(problem.seg)
    base = _quiet(cross_validate, problem, (), folds)
    mapped = _quiet(cross_validate, problem, ("soil_map",), folds)
    ratio = mapped.errors.sum() / base.errors.sum()
    assert ratio < 0.35, ratio  # 0.28 (turned) and 0.080 (disc and L) measured
    m = _quiet(fit, problem, ("soil_map",)).params["soil_map"]
    pos = problem.seg.pos[np.abs(problem.seg.dphi).sum(axis=-1) > 0]
    true = sum(np.where(r.contains(pos[:, 0], pos[:, 1]), r.compliance_per_nm, 0.0)
               for r in layout)
    agree = np.mean((m.compliance_at(pos) > 0.003) == (true > 0))
    assert agree > 0.9, agree  # 0.99 and 0.97 measured
    if layout is DISC_AND_L:  # the round patch is one disc of the map, where it lies
        discs = [shape for shape, _ in m.shapes() if isinstance(shape, Circle)]
        assert len(discs) == 1, m.layout()
        true_disc = layout[0]
        assert np.hypot(discs[0].center_x_m - true_disc.center_x_m,
                        discs[0].center_y_m - true_disc.center_y_m) < 0.1  # 0.02 m measured
        assert abs(discs[0].radius_m - true_disc.radius_m) < 0.1  # 0.009 m measured
    if layout is TURNED:  # the map's frame turns with the fields (modulo a quarter turn),
        # to within the search's last step and its quick proxy (26.25 deg measured for 29.8)
        off = (m.angle_rad - 0.52 + np.pi / 4) % (np.pi / 2) - np.pi / 4
        assert abs(off) < np.radians(5.0), np.degrees(m.angle_rad)


def test_a_maps_patches_hold_its_compliance_everywhere_overlaps_included():
    from slipenv.diagnose.effects.soil_map import _params
    from slipenv.diagnose.regions import DISC, RECT, Layout, disc

    # region 0 an L of two overlapping rectangles (a union), region 1 a rectangle across both
    # (adds), region 2 a disc over parts of both and of their overlap
    layout = Layout(((-3.0, -3.0, 1.0, -1.0), (-3.0, -3.0, -1.5, 2.0), (-2.0, -2.0, 2.5, 0.5),
                     disc((-0.5, 0.5), 1.5)), (0, 0, 1, 2), (RECT, RECT, RECT, DISC))
    m = _params(0.4, layout, np.array([0.004, 0.002, 0.001]))
    patches = m.patches()
    xy = np.random.default_rng(5).uniform(-5.0, 5.0, (8000, 2))
    painted = np.zeros(len(xy))
    for region, level in patches:  # PatchSoilMap: later patches on top
        inside = region.signed_distance_m(xy[:, 0], xy[:, 1]) < 0
        painted[inside] = level
    np.testing.assert_allclose(painted, m.compliance_at(xy), atol=1e-15)
    # every sum of the regions' compliances occurs
    assert set(np.round(m.compliance_at(xy), 6)) == \
        {0.0, 0.004, 0.002, 0.001, 0.006, 0.005, 0.003, 0.007}


def test_a_fitted_map_is_searched_with_no_shape_narrower_than_the_vehicles_track(
        field_problem, monkeypatch):
    """The replay looks the soil up at the body's centre: ground finer than the track is
    not resolved, so every search (frame angles, held-out shape counts, the map) is bounded."""
    seen = []
    search = regions.grow

    def spy(q, *args, **kwargs):
        seen.append(q.min_size_m)
        return search(q, *args, **kwargs)

    monkeypatch.setattr(regions, "grow", spy)
    m = _quiet(fit, field_problem, ("soil_map",)).params["soil_map"]
    track = float(np.median(field_problem.seg.track))
    assert track == pytest.approx(0.5) and seen
    np.testing.assert_allclose(seen, track)
    for u0, v0, u1, v1 in m.layout().rects:
        assert min(u1 - u0, v1 - v0) >= track - 1e-9


def test_the_fitted_map_is_applied_to_the_simulation_as_patches(field_problem, field_map):
    f = field_map
    report = {"format": "slipenv-diagnosis/1", "cause": "soil_map", "also": [],
              "parameters": f.report(field_problem.seg)}
    config = synth.base_config("diff_drive")
    extended = apply_model(config, report)
    assert isinstance(extended.soil_map, PatchSoilMap)
    soil_map = make_soil_map(extended.soil, extended.soil_map)
    base = make_soil_map(config.soil, config.soil_map)
    m = f.params["soil_map"]
    for x, y in ((-2.5, -2.5), (2.5, 2.5)):  # inside the two soft rectangles
        if m.compliance_at(np.array([x, y])) <= 0:
            continue
        assert soil_map.params_at(np.array([x]), np.array([y])) != \
            base.params_at(np.array([x]), np.array([y]))
    assert m.compliance_at(np.array([4.5, -4.0])) < 0.001  # firm ground stays firm


@pytest.mark.parametrize("kind", ["skid_steer", "rover4ws"])
def test_soil_regions_are_mapped_on_skid_steer_and_rover_logs(kind):
    """The map applies wherever torque slip does. The fields of ``REGIONS``
    under a skid-steer vehicle's and the rover's wheels: every wheel slips by its own torque
    times the compliance of the ground under the vehicle."""
    log = kinematic_log(3, None, duration_s=180.0, route="field", soil_regions=REGIONS,
                        kind=kind)
    problem = Problem.from_segments(build_segments([log]))
    m = _quiet(fit, problem, ("soil_map",)).params["soil_map"]
    pos = problem.seg.pos[np.abs(problem.seg.dphi).sum(axis=-1) > 0]
    fitted, true = m.compliance_at(pos), _truth_compliance(pos[:, 0], pos[:, 1])
    agree = np.mean((fitted > 0.5 * REGIONS[1].compliance_per_nm) == (true > 0))
    assert agree > 0.95, agree  # 0.99 (skid-steer) and 0.97 (rover) measured
    for level in (0.006, 0.008):  # within 5 % (0.4-1.7 % measured)
        near = np.isclose(true, level)
        assert abs(np.median(fitted[near]) - level) < 0.05 * level, (level, kind)
