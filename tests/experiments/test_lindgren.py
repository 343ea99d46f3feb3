"""`slipenv reproduce lindgren --quick`: the JSON contract and its targets, from a
real run; the offline filter passes and the helpers on their own."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

from slipenv.contracts.frame import SensorFrame
from slipenv.estimators.base import OdometryGeometry
from slipenv.estimators.lindgren.ekf import LindgrenEKF, LindgrenNoise, OracleSoil, Scheme
from slipenv.estimators.lindgren.models import TILT_SIGMA_RAD
from slipenv.experiments import experiment, lindgren
from slipenv.experiments.lindgren import report
from slipenv.experiments.lindgren.calibration import effective_radius_m, radius_from_recording
from slipenv.experiments.lindgren.filters import no_slip_odometry, replace_readings
from slipenv.experiments.lindgren.metrics import torque_slip
from slipenv.experiments.lindgren.recording import Recording
from slipenv.experiments.lindgren.report import finite
from slipenv.paths import path_by_name

BLOCK_REQUIRED = {
    "mean_deviation_m": {"no_slip_model", "slip_model", "scheme1", "scheme3", "scheme4"},
    "deviation_from_scheme1_m": {"no_slip_model", "slip_model", "scheme3", "scheme4"},
    "nis": {"no_slip_model", "slip_model", "band"},
    "autocorr_mean": {"no_slip_model", "slip_model"},
    "dropout_final_error_m": {"no_slip_model", "slip_model", "oracle"},
}


@pytest.fixture(scope="module")
def quick(tmp_path_factory) -> tuple[dict, dict, object]:
    """The quick experiment, seed 0, as the CLI runs it: headline and ablation block (about
    3 min on 2 cores)."""
    out = tmp_path_factory.mktemp("lindgren")
    result = experiment("lindgren")(quick=True, out_dir=str(out), json_path=str(out / "r.json"),
                                    seed=0, progress=False, docs_dir=str(out / "docs"))
    return result, json.loads((out / "r.json").read_text()), out


def test_json_has_both_blocks_with_the_required_keys_and_the_papers_numbers(quick) -> None:
    _, doc, _ = quick
    assert set(doc["metrics"]) == {"headline", "ablation"}
    for block in doc["metrics"].values():
        for key, names in BLOCK_REQUIRED.items():
            assert names <= set(block[key]), key
        assert block["slip_model_scheme"] in lindgren.SLIP_SCHEMES
        slip = block["slip_model_scheme"]
        # slip_model is the named scheme, the best of the slip-model schemes after the cut
        assert block["dropout_final_error_m"]["slip_model"] == min(
            block["slip_model_schemes_final_error_m"].values())
        assert block["mean_deviation_m"]["slip_model"] == block["mean_deviation_m"][slip]
        assert block["deviation_from_scheme1_m"]["slip_model"] == (
            block["deviation_from_scheme1_m"][slip])
        # the judged circle measure is the mean error against the truth
        assert block["mean_deviation_m"]["scheme3"] == block["circles"]["mean_deviation_m"][
            "scheme3"]
        assert "scheme1" not in block["deviation_from_scheme1_m"]
        assert block["nis"]["slip_model"] == block["nis"][slip]
        assert block["dropout_final_error_m"]["no_slip_model"] == (
            block["dropout"]["final_error_m"]["scheme3"])
        lo, hi = block["nis"]["band"]
        assert 1.7 < lo < 2.0 < hi < 2.3  # exact 95 % band for K ~ 200-1000, n_z = 2
        assert all(isinstance(v, float) and v >= 0.0
                   for v in block["dropout_final_error_m"].values())
    assert doc["paper"]["mean_deviation_m"] == {"scheme3": 0.243, "scheme4": 0.127}  # Table 1
    assert doc["paper"]["nis"]["band"] == [1.8831, 2.1204]  # Eq. 44, K = 1099
    assert doc["paper"]["dropout_final_error_m"]["slip_model"] == 0.21  # Fig. 7
    assert doc["config"]["quick"] is True and doc["config"]["steered_by"] == "scheme 1"
    assert set(doc["targets"]) == {"headline", "ablation"}


def test_headline_world_is_the_one_the_filter_does_not_assume(quick) -> None:
    """Curved law in the world, the estimator's default process noise, per-wheel radii
    measured on a calibration drive; the ablation differs only in the world's law."""
    _, doc, _ = quick
    blocks = doc["config"]["blocks"]
    assert blocks["headline"]["force_model"] == "janosi"
    assert "linear" in blocks["ablation"]["force_model"]
    defaults = LindgrenNoise()
    for b in blocks.values():
        assert b["soil_noise"] == {"radius_var_per_m": defaults.radius_var_per_m,
                                   "k_s_rel_var_per_m": defaults.k_s_rel_var_per_m}
        assert b["filter"] == {"bearing_gate_prob": 1.0}  # the paper's association only
    cal = blocks["headline"]["calibration"]
    soil = doc["metrics"]["headline"]["circles"]["soil_true"]
    for r_eff, r_true, slip in zip(cal["radius_per_side_m"], soil["R_w_m"], cal["slip_per_side"],
                                   strict=True):
        assert r_eff == pytest.approx(r_true * (1.0 - slip))
        assert 0.0 < slip < 0.5  # driving torque > 0: the wheels slip
    # the curved law is softer than its zero-slip slope at any torque > 0
    assert cal["k_s_secant_nm"] < min(soil["k_s"])


def test_headline_slip_model_wins_on_the_circles_against_the_truth(quick) -> None:
    """On the circles the slip model (with the lateral slip gain) is at most 0.7 x the no-slip
    model's true mean error, and its NIS is closer to the band (Table 3), in the world it
    does not assume; without k_β scheme 4's true error is several times larger."""
    tg = quick[0]["targets"]["headline"]
    assert tg["slip_model NIS closer to band than no_slip_model"]["met"]
    assert tg["slip_model mean error <= 0.7 no_slip_model"]["met"]
    m = quick[1]["metrics"]["headline"]
    true = m["circles"]["mean_deviation_m"]
    assert true[m["slip_model_scheme"]] <= 0.7 * true["scheme3"]
    assert true["scheme4"] < 0.5 * true["scheme4_no_lateral"]


def test_ablation_slip_model_wins_on_the_circles_against_the_truth(quick) -> None:
    """In the filter's own linear world the slip model is at most 0.7 x the no-slip model's
    mean error against the truth on the circles, too."""
    assert quick[0]["targets"]["ablation"]["slip_model mean error <= 0.7 no_slip_model"]["met"]


@pytest.mark.xfail(strict=True, reason=(
    "the paper's measure, missed in the headline world since the slip model carries the "
    "lateral slip gain (quick run, seed 0: deviation from scheme 1 0.113 m against the no-slip "
    "model's 0.107 m; full run 0.121 against 0.089): the reference, scheme 1, has no lateral "
    "state and is itself 0.12 m off the truth; against the truth, the judged measure, the slip "
    "model is 0.023 m off against 0.19 m (full run 0.024 against 0.173), met above"))
def test_headline_slip_model_deviates_at_most_0_7_no_slip_model_from_scheme_1(quick) -> None:
    """Table 1: the slip model deviates at most 0.7 x the no-slip model from scheme 1."""
    tg = quick[0]["targets"]["headline"]
    assert tg["slip_model deviation from scheme 1 <= 0.7 no_slip_model"]["met"]


@pytest.mark.xfail(strict=True, reason=(
    "missed in the headline world (quick run, seed 0: the slip model's NIS 2.20 against the "
    "band 1.87-2.13, scheme 4 with k_β; full run 2.15 against 1.90-2.10): the missing effect "
    "is the world's curved torque-slip law, which the filter's linear law cannot follow; in "
    "the ablation's linear world, the same drives and filter, the NIS is 1.69 (full run "
    "1.72), below its band (the next test)"))
def test_headline_slip_model_nis_inside_the_band(quick) -> None:
    assert quick[0]["targets"]["headline"]["slip_model NIS inside the 95 % band"]["met"]


def test_the_curved_law_lifts_the_slip_models_nis_from_below_the_band_in_the_linear_world(
        quick) -> None:
    """The two blocks differ only by the world's force law. With the filter's own linear law in
    the world, the paper's odometer variance (0.25 count²) exceeds the simulated encoders'
    quantisation (1/6 count²), so the NIS lies below its band; the curved law adds the model
    error that no state carries and lifts it by a clear margin."""
    h, a = quick[1]["metrics"]["headline"], quick[1]["metrics"]["ablation"]
    assert h["slip_model_scheme"] == a["slip_model_scheme"]
    assert a["nis"]["slip_model"] < a["nis"]["band"][0]
    assert h["nis"]["slip_model"] > a["nis"]["slip_model"] + 0.2


@pytest.mark.xfail(strict=True, reason=(
    "missed in the headline world (quick run, seed 0, 12 drives: slip model 10.9 m against "
    "the no-slip model's 17.2 m with measured per-wheel radii, ratio 0.63; full run 14.1 "
    "against 25.7 m, 0.55; no drive diverges, 9.5-12.9 m and 10.8-18.0 m per drive): one "
    "k_s per side cannot fit the curved law's straights and turns (the page measures the "
    "secant T/s: ~535 N m straight, ~400 N m outer wheel in the turns); the scheme-4 oracle "
    "given the calibration drive's secant ends ~6.7 m off"))
def test_headline_slip_model_within_0_3_no_slip_model_after_the_cut(quick) -> None:
    assert quick[0]["targets"]["headline"]["slip_model <= 0.3 no_slip_model"]["met"]


def test_headline_slip_model_beats_the_no_slip_model_after_the_cut(quick) -> None:
    """What holds of the missed target above: the slip model still ends closer than the
    no-slip model with measured per-wheel radii."""
    drop = quick[1]["metrics"]["headline"]["dropout_final_error_m"]
    assert drop["slip_model"] < drop["no_slip_model"]


def test_headline_oracle_target_compares_with_no_oracle(quick) -> None:
    """The 1.5 x oracle target: the oracle knows the true radii and the law's slope at zero
    slip, which on the curved law is no oracle, so its target is met trivially; given the
    calibration drive's secant instead, the oracle does better than with the tangent."""
    final = quick[1]["metrics"]["headline"]["dropout"]["final_error_m"]
    assert quick[0]["targets"]["headline"]["slip_model <= 1.5 oracle"]["met"]
    assert final["oracle_secant"] < final["oracle"]


def test_whiteness_slip_model_innovations_white_no_slip_biased(quick) -> None:
    """Table 2 in both worlds: the slip model's odometric innovations are near white, the
    no-slip model's are biased (all of its autocorrelation outside the interval)."""
    for m in quick[1]["metrics"].values():
        assert abs(m["autocorr_mean"]["slip_model"]) < 0.05 < 0.2 < m["autocorr_mean"][
            "no_slip_model"]
        assert m["autocorr_share_inside"]["slip_model"] > 0.8 > m["autocorr_share_inside"][
            "no_slip_model"]


def test_ablation_slip_model_loses_most_to_the_soil_random_walk_after_the_cut(quick) -> None:
    """In the filter's own linear world, scheme 4 after the cut loses most of its accuracy to
    the walk of its soil states along the unobservable scale: with the random walk a uniform
    field needs, or with bearings until twice the time, it ends at most half as far off."""
    final = quick[1]["metrics"]["ablation"]["dropout"]["final_error_m"]
    assert final["scheme4_field_soil_noise"] < 0.5 * final["scheme4"]
    assert final["scheme4_cut_x2"] < 0.5 * final["scheme4"]


def test_slip_model_is_overconfident_after_the_cut_only_where_the_law_is_curved(quick) -> None:
    """The pose NEES after the laser cut: in the filter's own linear world the slip model's is
    a few times n = 3, in the curved world several times more (one k_s per side cannot hold
    the straights and the turns), while its tilt, unmeasured on these drives, stays within a
    few standard deviations of the field's slope prior."""
    head, abl = (quick[1]["metrics"][b] for b in ("headline", "ablation"))
    n_head = head["dropout"]["nees_after_cut"][head["slip_model_scheme"]]
    n_abl = abl["dropout"]["nees_after_cut"][abl["slip_model_scheme"]]
    hi = head["dropout"]["nees_after_cut_band_if_independent"][1]
    assert hi < n_abl < 60.0
    assert n_head > 3.0 * n_abl
    sigma_deg = math.degrees(TILT_SIGMA_RAD)
    for m in (head, abl):
        assert m["dropout"]["max_tilt_deg"][m["slip_model_scheme"]] < 4.0 * sigma_deg


def test_operating_point_sits_on_the_curves_bend(quick) -> None:
    """The headline calibration drive: the secant over the law's zero-slip slope is < 1 and
    read on Okello's curve (Eq. 21) gives x = s/B near the preset's K/L; the linear world's
    secant is its slope (ratio ~1)."""
    m = quick[1]["metrics"]
    op = m["headline"]["operating_point"]
    assert 0.0 < op["secant_over_tangent"] < 0.9
    assert op["b_measured"] == pytest.approx(op["b_preset"], rel=0.15)
    assert op["slip"] > op["linear_slip"] > 0.0  # the curve slips more than its tangent says
    assert 0.0 < op["resistance_share"] < 0.5
    assert m["ablation"]["operating_point"]["secant_over_tangent"] == pytest.approx(1.0,
                                                                                   abs=0.05)


def test_truth_side_metrics_and_plots(quick) -> None:
    """What only a simulation has: true errors and soil truth; every figure written."""
    _, doc, out = quick
    for m in doc["metrics"].values():
        c = m["circles"]
        slip = m["slip_model_scheme"]
        assert c["mean_deviation_m"][slip] < 0.15
        assert c["soil_true"]["R_w_m"] == [0.283, 0.287]  # Lindgren §3.2, on soil
        drives = m["dropout"]["final_error_m_per_drive"]
        assert len(drives["scheme4"]) == lindgren.QUICK.dropout_drives
    # the no-slip model is biased on the curved law's circles
    c = doc["metrics"]["headline"]["circles"]
    assert c["mean_deviation_m"]["scheme3"] > c["mean_deviation_m"][
        doc["metrics"]["headline"]["slip_model_scheme"]]
    for name in ("paths.png", "dropout.png", "autocorrelation.png", "paths_ablation.png",
                 "dropout_ablation.png"):
        assert (out / name).stat().st_size > 10_000


def test_the_results_page_holds_the_command_the_table_the_blocks_and_the_figures(
        quick) -> None:
    result, doc, out = quick
    page = (out / "docs" / "lindgren.md").read_text()
    assert f"`slipenv reproduce lindgren --quick --seed 0 --docs {out / 'docs'}`" in page
    m = result["metrics"]
    no_slip = [m[b]["deviation_from_scheme1_m"]["no_slip_model"] for b in ("headline",
                                                                          "ablation")]
    assert ("| deviation from scheme 1 [m] (the paper's Table 1), no_slip_model (scheme3) | "
            f"0.243 | {no_slip[0]:.4g} | {no_slip[1]:.4g} |") in page  # Table 1
    true = [m[b]["mean_deviation_m"]["slip_model"] for b in ("headline", "ablation")]
    assert (f"| mean error against the truth [m], slip_model | - | {true[0]:.4g} | "
            f"{true[1]:.4g} |") in page  # the judged measure: the paper has no truth
    assert "**Which circle measure is which.**" in page
    slip = [m[b]["dropout_final_error_m"]["slip_model"] for b in ("headline", "ablation")]
    assert (f"| final position error [m], slip_model | 0.21 | {slip[0]:.4g} | {slip[1]:.4g} |"
            in page)
    for heading in ("## The two blocks: which world, which settings, what is calibrated on what",
                    "## The paper's regime: where the field's operating point sits",
                    "## Ablation: the filter's own linear law in the world"):
        assert heading in page
    assert "| headline | curved Janosi/Okello law" in page
    for name in ("paths", "dropout", "autocorrelation", "paths_ablation", "dropout_ablation"):
        assert f"(img/lindgren/{name}.png)" in page
        assert (out / "docs" / "img" / "lindgren" / f"{name}.png").stat().st_size > 10_000
    assert "{" not in page  # every placeholder filled


def test_effective_radius_is_distance_over_wheel_angle() -> None:
    """A wheel of radius 0.3 m rolling 5 m without slip turns 5/0.3 rad."""
    assert effective_radius_m(5.0, [5.0 / 0.3]) == pytest.approx(0.3, rel=1e-12)
    assert effective_radius_m(5.0, [5.0 / 0.29, 5.0 / 0.31]) == pytest.approx(
        5.0 / np.mean([5.0 / 0.29, 5.0 / 0.31]))
    for bad in ((0.0, [1.0]), (1.0, [0.0]), (1.0, [math.nan]), (-1.0, [1.0])):
        with pytest.raises(ValueError):
            effective_radius_m(*bad)


def _kinematic_recording(radius: float = 0.2851, right_radius: float | None = None) -> Recording:
    """Quantised encoders (285 counts/rad) of two slip-free wheels (left ``radius``, right
    ``right_radius``, default the same) on a 6 m straight: 0.25 m/s² to 0.5 m/s, then constant
    speed."""
    right_radius = radius if right_radius is None else right_radius
    cpr, dt = 285.0, 0.05
    t = np.arange(0.0, 14.0, dt)
    s = np.where(t < 2.0, 0.125 * t**2, 0.5 + 0.5 * (t - 2.0))  # 0.25 m/s² to 0.5 m/s
    s = np.minimum(s, 6.0)
    counts = np.floor(np.column_stack([s / radius, s / right_radius]) * cpr).astype(np.int64)
    frames = [SensorFrame(float(tk), c, np.zeros(2)) for tk, c in zip(t, counts, strict=True)]
    geom = OdometryGeometry(wheel_radius_m=0.275, track_width_m=1.5, counts_per_rad=cpr)
    truth = np.column_stack([s, np.zeros_like(s), np.zeros_like(s)])
    return Recording(path=path_by_name("straight", length_m=6.0), frames=frames, t_s=t,
                     truth=truth, s_true_m=s,
                     oracle=OracleSoil((radius, right_radius), (700.0, 700.0)),
                     params=LindgrenNoise(), geometry=geom, beacons_xy=np.zeros((0, 2)))


def test_calibration_recovers_the_rolling_radius_of_a_kinematic_drive() -> None:
    """Quantised encoders on a slip-free 6 m straight with a start-up: R_eff = the true radius
    (within the quantisation, 1 count in ~4000), the start-up left out by the marks."""
    radius = 0.2851
    rec = _kinematic_recording(radius)
    cal = radius_from_recording(rec, settle_m=1.0)
    assert cal["radius_m"] == pytest.approx(radius, rel=5e-4)
    assert cal["distance_m"] == pytest.approx(4.0, abs=0.03)
    assert abs(cal["slip_vs_true_radius"]) < 5e-4
    with pytest.raises(ValueError, match="too short"):
        radius_from_recording(rec, settle_m=3.5)


def test_calibration_measures_each_wheel_separately() -> None:
    """Lindgren §3.2's 0.283 / 0.287 m: two slip-free wheels of different radii on a straight
    each give their own radius; the one-radius measurement lies between them."""
    rec = _kinematic_recording(0.283, 0.287)
    cal = radius_from_recording(rec, settle_m=1.0)
    assert cal["radius_per_side_m"] == pytest.approx([0.283, 0.287], rel=5e-4)
    assert cal["distance_per_side_m"] == pytest.approx([cal["distance_m"]] * 2, rel=1e-9)
    assert 0.283 < cal["radius_m"] < 0.287
    assert np.abs(cal["slip_per_side"]).max() < 5e-4


def test_per_wheel_count_scale_gives_a_one_radius_filter_each_wheels_distance() -> None:
    """Counts scaled by R_i / R, read with the one radius R, give each wheel's own distance
    c R_i / Γ (the no-slip model, Lindgren Eq. 15, is linear in the counts)."""
    geom = OdometryGeometry(wheel_radius_m=0.275, track_width_m=1.6, counts_per_rad=285.0)
    radius, scale = no_slip_odometry((0.24, 0.25), geom)
    assert radius == pytest.approx(0.245)
    counts = np.array([1000.0, 1000.0])
    distance = counts * scale * radius / geom.counts_per_rad
    assert distance == pytest.approx(counts * np.array([0.24, 0.25]) / geom.counts_per_rad)


def test_replaced_readings_are_the_frame_dataclasses_replace_gives() -> None:
    """The offline passes change a frame's readings without SensorFrame's ``__init__``: the
    same frame as ``dataclasses.replace``, frozen, and the recorded frame left as it was."""
    frame = SensorFrame(1.0, np.array([10, 20]), np.array([3.0, 4.0]), gyro_z_rad_s=0.1,
                        pitch_rad=0.02, beacon_bearings_rad=np.array([0.2]),
                        beacon_times_s=np.array([0.95]))
    changes = {"enc_counts": frame.enc_counts * np.array([0.9, 1.1]), "gyro_z_rad_s": math.nan,
               "pitch_rad": math.nan, "beacon_bearings_rad": np.zeros(0),
               "beacon_times_s": np.zeros(0)}
    new = replace_readings(frame, changes)
    assert type(new) is SensorFrame and new == dataclasses.replace(frame, **changes)
    assert new.wheel_torque_nm is frame.wheel_torque_nm and new.t_s == 1.0
    assert frame.gyro_z_rad_s == 0.1 and len(frame.beacon_times_s) == 1
    with pytest.raises(dataclasses.FrozenInstanceError):
        new.t_s = 2.0  # type: ignore[misc]
    # valid only while SensorFrame's __init__ sets the fields and checks nothing
    assert not hasattr(SensorFrame, "__post_init__")


def test_okello_curve_position_inverts_the_secant_ratio() -> None:
    """On Okello's curve (Lindgren Eq. 21) T/T_max = g(x) = 1 - (1 - e^-x)/x and the secant
    over the zero-slip slope T_max/(2B) (Eq. 24) is 2 g(x)/x; small x: 1 - x/3 (Eq. 23)."""
    for x in (0.05, 0.5, 1.2, 4.0):
        g = 1.0 - (1.0 - math.exp(-x)) / x
        assert lindgren.okello_bracket(x) == pytest.approx(g, rel=1e-9)
        assert lindgren.curve_position(2.0 * g / x) == pytest.approx(x, rel=1e-6)
    assert lindgren.curve_position(1.0 - 0.01 / 3.0) == pytest.approx(0.01, rel=0.01)
    assert lindgren.curve_position(1.0) == 0.0  # a linear law: at the origin
    assert lindgren.okello_bracket(1e-4) == pytest.approx(0.5e-4, rel=1e-3)  # T ~ k_s s


def test_calibration_on_a_simulated_drive_recovers_the_rolling_radius(short_drive) -> None:
    """On Lindgren's linear law the wheels slip s = T/k_s (Eq. 24), so the measured effective
    radius is R_w (1 - T/k_s) with R_w the true rolling radius (Eq. 25): undoing that slip
    recovers R_w to within 1 % of the slip's own size."""
    cal = radius_from_recording(short_drive, settle_m=1.0)
    k_s = np.mean(short_drive.oracle.k_s)
    slip = float(np.mean(cal["mean_torque_nm"])) / k_s
    assert 0.005 < slip < 0.3
    r_true = float(np.mean(short_drive.oracle.wheel_radius_m))
    assert cal["radius_m"] / (1.0 - slip) == pytest.approx(r_true, rel=0.01 * slip + 2e-4)
    assert abs(cal["radius_m"] - r_true) > 0.5 * slip * r_true  # the slip is really there


def test_linear_world_has_one_torque_slip_gradient(short_drive) -> None:
    """On Lindgren's linear law T = k_s s (Eq. 24): the secant T/s of the simulated straight
    drive is the oracle's k_s (what the curved world of the robust block does not have)."""
    straight = torque_slip(short_drive)["straight"]
    assert straight["k_s_secant_nm"] == pytest.approx(np.mean(short_drive.oracle.k_s), rel=0.1)
    assert 0.0 < straight["slip"] < 0.3


def test_variant_and_setting_options_are_validated() -> None:
    from slipenv.experiments.lindgren.settings import Setting, Variant

    with pytest.raises(ValueError, match="Variant.scheme"):
        Variant("scheme9")
    with pytest.raises(ValueError, match="Variant.noise"):
        Variant("scheme4", {"no_such_noise": 1.0})
    with pytest.raises(ValueError, match="Variant.secant_k_s"):
        Variant("scheme4", secant_k_s=True)
    with pytest.raises(ValueError, match="Variant.cut_factor"):
        Variant("oracle", cut_factor=0.0)
    with pytest.raises(ValueError, match="exclude each other"):
        Variant("scheme3", nominal_radius=True, one_radius=True)
    with pytest.raises(ValueError, match="Variant.lateral"):  # no-slip: the paper's filter
        Variant("scheme3", lateral=True)
    with pytest.raises(ValueError, match="Setting.variants"):
        Setting("x", "w", None, {}, measured_radius=False,
                variants={"scheme4": Variant("scheme4")})
    assert "oracle_secant" in lindgren.HEADLINE.circle_filters
    assert "scheme4_cut_x2" not in lindgren.HEADLINE.circle_filters  # only moves the cut
    with pytest.raises(ValueError, match="calibration"):  # the secant needs a calibration
        lindgren.run_filter(_kinematic_recording(), "oracle_secant",
                            variants=lindgren.HEADLINE.variants)


@pytest.fixture(scope="module")
def short_drive():
    """8 s straight in the ablation's linear world, recorded as the experiment records its
    drives (no calibration: the nominal radius)."""
    return lindgren.record(path_by_name("straight", length_m=4.0, speed_mps=0.5), seed=3,
                           setting=lindgren.ABLATION)


def test_offline_pass_cuts_bearings_and_removes_inertial_data(short_drive) -> None:
    rec = short_drive
    assert len(rec.frames) == len(rec.truth) == len(rec.t_s)
    run = lindgren.run_filter(rec, "scheme4", cut_s=4.0, inertial=False)
    times = [t for t, _, _ in run.ekf.history["bearing"]]
    assert times and max(times) <= 4.0
    assert run.ekf.history["gyro"] == [] and run.ekf.history["acc"] == []
    assert run.ekf.skipped["gyro_nan"] == len(rec.frames) - 1
    assert run.est.shape == (len(rec.frames), 3) and run.P.shape == (len(rec.frames), 3, 3)
    full = lindgren.run_filter(rec, "scheme4")
    assert len(full.ekf.history["gyro"]) == len(rec.frames) - 1
    oracle = lindgren.run_filter(rec, "oracle")
    assert oracle.ekf.oracle == rec.oracle and oracle.ekf.n == 9


def test_filters_use_the_papers_ungated_association_and_default_noise(short_drive) -> None:
    """FILTER departs from the estimator defaults in the bearing association only; the
    variants put the gate back or cut the soil random walk to a uniform field's."""
    assert short_drive.params.bearing_gate_prob == 1.0
    assert short_drive.params.radius_var_per_m == LindgrenNoise().radius_var_per_m
    assert short_drive.params.k_s_rel_var_per_m == LindgrenNoise().k_s_rel_var_per_m
    variants = lindgren.ABLATION.variants
    gated = lindgren.run_filter(short_drive, "scheme3_gated", variants=variants)
    assert gated.ekf.scheme == Scheme.ALL_NO_SLIP
    assert gated.ekf.params.bearing_gate_prob == LindgrenNoise().bearing_gate_prob
    soil = lindgren.run_filter(short_drive, "scheme4_field_soil_noise", variants=variants)
    assert soil.ekf.params.radius_var_per_m == lindgren.FIELD_NOISE["radius_var_per_m"]
    assert soil.ekf.params.k_s_rel_var_per_m == lindgren.FIELD_NOISE["k_s_rel_var_per_m"]
    assert soil.ekf.params.bearing_gate_prob == 1.0


def test_slip_model_schemes_carry_the_lateral_slip_gain_and_the_papers_filters_do_not(
        short_drive) -> None:
    """The slip-model schemes carry k_β with FarmField-v0's prior, as the farm vehicle's EKF;
    the no-slip schemes and the oracle keep the paper's state; in both blocks one variant
    takes k_β out of scheme 4 and one puts it into the oracle."""
    from slipenv.envs.registration import PRESETS

    sigma0 = PRESETS["slipenv/FarmField-v0"]["estimator_kwargs"]["params"]["lateral_slip_sigma0"]
    for block in (lindgren.HEADLINE, lindgren.ABLATION):
        assert {"scheme4_no_lateral", "oracle_lateral"} <= set(block.variants)
    v = lindgren.ABLATION.variants
    n = {name: lindgren.run_filter(short_drive, name, cut_s=2.0, variants=v).ekf
         for name in ("scheme3", "scheme4", "scheme4_no_lateral", "oracle", "oracle_lateral")}
    assert n["scheme4"].lateral_slip and n["scheme4"].params.lateral_slip_sigma0 == sigma0
    assert n["scheme4"].n == 14 and n["scheme4_no_lateral"].n == 13
    assert not n["scheme3"].lateral_slip and n["scheme3"].n == 9
    assert n["oracle"].n == 9 and n["oracle_lateral"].n == 10
    if "scheme5" in lindgren.SLIP_SCHEMES:
        assert lindgren.run_filter(short_drive, "scheme5", cut_s=2.0).ekf.n == 16


def test_gate_probability_one_disables_the_bearing_gate() -> None:
    """Lindgren §2.4: nearest-innovation association alone; a bearing far from every beacon
    is still associated and used (the default gate would reject it)."""
    beacons = np.array([[10.0, 0.0], [0.0, 10.0], [-10.0, 0.0], [0.0, -10.0]])
    geom = OdometryGeometry(wheel_radius_m=0.275, track_width_m=1.5, counts_per_rad=285.0)
    start = SensorFrame(0.0, np.zeros(2), np.zeros(2))
    outlier = SensorFrame(0.05, np.zeros(2), np.zeros(2), beacon_bearings_rad=np.array([0.6]),
                          beacon_times_s=np.array([0.05]))
    used = {}
    for prob in (0.999, 1.0):
        ekf = LindgrenEKF(geom, 1, LindgrenNoise(bearing_gate_prob=prob), beacons_xy=beacons)
        ekf.reset(0.0, 0.0, 0.0, start)
        ekf.update(outlier)
        used[prob] = len(ekf.history["bearing"])
    assert used == {0.999: 0, 1.0: 1}
    with pytest.raises(ValueError, match="bearing_gate_prob"):
        LindgrenNoise(bearing_gate_prob=1.5)


def test_same_seed_same_recording(short_drive) -> None:
    again = lindgren.record(path_by_name("straight", length_m=4.0, speed_mps=0.5), seed=3,
                            setting=lindgren.ABLATION)
    np.testing.assert_array_equal(again.truth, short_drive.truth)
    np.testing.assert_array_equal(again.frames[-1].enc_counts, short_drive.frames[-1].enc_counts)


def test_nis_distance_and_targets() -> None:
    assert report.nis_distance(2.0, [1.9, 2.1]) == 0.0
    assert report.nis_distance(1.6, [1.9, 2.1]) == pytest.approx(0.3)
    assert report.nis_distance(5.0, [1.9, 2.1]) == pytest.approx(2.9)
    m = {"mean_deviation_m": {"no_slip_model": 0.4, "slip_model": 0.3},
         "deviation_from_scheme1_m": {"no_slip_model": 0.4, "slip_model": 0.2},
         "nis": {"no_slip_model": 2.5, "slip_model": 1.0, "band": [1.9, 2.1]},
         "dropout_final_error_m": {"no_slip_model": 2.0, "slip_model": 0.5, "oracle": 0.4}}
    met = {k: t["met"] for k, t in report.targets(m).items()}
    assert met == {"slip_model mean error <= 0.7 no_slip_model": False,
                   "slip_model deviation from scheme 1 <= 0.7 no_slip_model": True,
                   "slip_model NIS inside the 95 % band": False,
                   "slip_model NIS closer to band than no_slip_model": False,
                   "slip_model <= 0.3 no_slip_model": True,
                   "slip_model <= 1.5 oracle": True}
    m["nis"]["slip_model"] = 2.0
    assert report.targets(m)["slip_model NIS inside the 95 % band"]["met"]


def test_json_sanitiser_makes_standard_json() -> None:
    doc = finite({"a": math.nan, "b": [np.float64(1.5), np.int64(2), math.inf], "c": None})
    assert doc == {"a": None, "b": [1.5, 2, None], "c": None}
    json.dumps(doc, allow_nan=False)
