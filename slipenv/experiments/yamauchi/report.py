"""The paper-vs-simulation table of ``slipenv reproduce yamauchi``.

:func:`table_rows` is the one source of the table: :func:`format_table` prints it, the results
page (:mod:`.docs`) renders the same rows in Markdown. Rows whose label starts with
``limit:`` are measured limits, ``target:`` rows the reproduction's targets.
"""

from __future__ import annotations


def table_rows(result: dict) -> list[tuple[str, str, str]]:
    """(quantity, paper, simulation), one row per reported number."""
    m, paper = result["metrics"], result["paper"]
    pf, ppf = m["path_following"], paper["path_following"]
    odo = m["odometry_rmse_m"]
    rows = [(f"Endo n, tilt {t}° [95 % CI]", f"{paper['endo_n'][t]:.3f}",
             f"{m['endo_n'][t]:.3f} [{m['endo_n_ci95'][t][0]:.3f}, "
             f"{m['endo_n_ci95'][t][1]:.3f}]") for t in m["endo_n"]]
    training = m.get("endo_n_training")
    if training:  # the n the odometry and the circle use: no held-out run in it
        rows.append(("  same, training runs only (the odometry's and circle's n), tilt "
                     + "/".join(training) + "°", "-",
                     " / ".join(f"{v:.3f}" for v in training.values())))
    rows += [("slip angle RMSE, held-out runs [deg]", "(Fig. 5)",
              f"{m['slip_angle_rmse_deg']:.2f}")]
    rows += [(f"odometry RMSE {k} [m]", "-", f"{v:.4f}") for k, v in odo.items()]
    rows += [("odometry RMSE improvement vs gyrodometry",
              f"{100 * paper['odometry_improvement_vs_gyrodometry']:.0f} %",
              f"{100 * m['odometry_improvement_vs_gyrodometry']:.0f} %")]
    if m.get("clockwise"):
        cw = m["clockwise"]["odometry_rmse_m"]
        rows.append(("  same, clockwise runs (own Eq. 9 fit)", "-",
                     f"{100 * (1 - cw['slip_compensated'] / cw['gyrodometry']):.0f} %"))
    ratios = m.get("odometry_rmse_ratio") or {}
    split = m.get("odometry_rmse_ratio_endo_n_by_direction")
    if set(ratios) == {"ccw", "cw"}:
        rows.append(("odometry RMSE slip-compensated / gyrodometry, held-out runs, ccw / cw",
                     f"{1 - paper['odometry_improvement_vs_gyrodometry']:.2f}",
                     f"{ratios['ccw']:.2f} / {ratios['cw']:.2f}"))
    cv = m.get("odometry_rmse_ratio_cross_validated")
    if cv:
        folds = result["settings"].get("cv_folds", 3)
        rows.append((f"  same, {folds}-fold cross-validated by run (every run held out once)",
                     "-", f"{cv['ccw']:.2f} / {cv['cw']:.2f}"))
    if split:
        rows.append(("  same, Endo n per tilt and turning direction (training runs, Eq. 9 "
                     "refitted on its regressors)", "-", f"{split['ccw']:.2f} / {split['cw']:.2f}"))
    n_split = m.get("endo_n_training_by_direction") or {}
    if n_split and None not in n_split.values():
        rows.append(("  Endo n per turning direction ccw / cw, training runs only", "-",
                     ", ".join(f"{t}° {n_split[t + '_ccw']:.2f} / {n_split[t + '_cw']:.2f}"
                               for t in m["endo_n"])))
    labels = {"feedback_gyrodometry": "Eq. 9 on gyrodometry (paper's conventional)",
              "feedback": "Eq. 9 on slip-compensated odometry",
              "feedforward": "Eq. 10 (β feed-forward) on slip-compensated"}
    for key, label in labels.items():
        p = ppf.get(key, {}).get("mean_error_m")
        rows.append((f"circle 15°, {label}: mean error [cm]",
                     "-" if p is None else f"{100 * p:.1f}",
                     f"{100 * pf[key]['mean_error_m']:.1f} (RMSE {100 * pf[key]['rmse_m']:.1f},"
                     f" {pf[key]['completed']}/{len(pf[key]['per_seed_mean_error_m'])} laps)"))
    rows.append(("circle RMSE improvement, Eq. 10 vs Eq. 9 on gyrodometry",
                 f"{100 * ppf['rmse_improvement']:.0f} %",
                 f"{100 * pf['rmse_improvement_vs_gyrodometry_feedback']:.0f} %"))
    rows.append(("circle RMSE improvement, Eq. 10 vs Eq. 9 (same odometry)", "-",
                 f"{100 * pf['rmse_improvement']:.0f} %"))
    search = pf.get("rigid_ground_rmse_m_by_pole")
    if search:  # why the headline pole: the gain search on a solid floor (§3.1)
        rows.append(("circle gains: rigid-ground search (Eq. 9 on gyrodometry, concrete), lap "
                     f"RMSE at {'/'.join(search)} rad/s [cm]", "-",
                     " / ".join(f"{100 * v:.2f}" for v in search.values())
                     + f" ({pf['pole_rps']:g} chosen)"))
    lim = m["limits"]
    by_dir = m.get("endo_n_by_direction") or {}
    for t in m["endo_n"]:
        up, down = by_dir.get(f"{t}_ccw"), by_dir.get(f"{t}_cw")
        if t == "0" or up is None or down is None:
            continue
        rows.append((f"limit: Endo n, tilt {t}°, fitted turning uphill / downhill "
                     "(Eq. 8 has one n for both)", "-", f"{up:.2f} / {down:.2f}"))
    share = lim.get("endo_common_mode_share")
    if share:
        rows.append(("limit: rotation samples whose true slips break Eq. 8's sign (both "
                     "tracks slip the same way), tilt " + "/".join(f"{t}" for t in share)
                     + "°", "-", " / ".join(f"{100 * v:.0f} %" for v in share.values())))
    ratio = lim["odometry_ratio_to_gyrodometry"]
    both = lim.get("odometry_ratio_to_gyrodometry_by_direction") or {}
    cw_lim = both.get("cw")
    ways = ", ccw / cw" if cw_lim else ""

    def ccw_cw(key: str) -> str:
        return f"{ratio[key]:.2f}" + (f" / {cw_lim[key]:.2f}" if cw_lim else "")

    rows.append(("limit: slip-compensated with the true β, RMSE / gyrodometry"
                 + ways, "-",
                 f"{ccw_cw('slip_compensated_true_beta')} (Eq. 9: {ccw_cw('slip_compensated')};"
                 " the rest is Endo's slip ratios)"))
    if "slip_compensated_true_slips" in ratio:
        rows.append(("limit: slip-compensated with the true track slips (Eq. 9's β), RMSE / "
                     "gyrodometry" + ways, "-",
                     f"{ccw_cw('slip_compensated_true_slips')} (the rest is Eq. 9's β)"))
        rows.append(("limit: slip-compensated with the true track slips and the true β, RMSE "
                     "/ gyrodometry" + ways, "-",
                     f"{ccw_cw('slip_compensated_true_slips_true_beta')} (the gyro's heading "
                     "error)"))
    fall = lim.get("fall_line_start")
    if fall:
        n, ratio_fl = fall["endo_n"], fall["odometry_rmse_ratio"]
        rows.append(("limit: rotation runs started facing downhill (§2.3 does not say which "
                     "side of the field was raised): Endo n, tilt " + "/".join(n) + "°; "
                     "slip-compensated / gyrodometry, held-out runs, ccw / cw", "-",
                     " / ".join(f"{v:.2f}" for v in n.values())
                     + f"; {ratio_fl['ccw']:.2f} / {ratio_fl['cw']:.2f}"))
    r2 = lim.get("endo_r2")
    if r2:
        rows.append(("limit: R² of Eq. 8 (log slip ratio against n log speed ratio) on the "
                     "true slips, tilt " + "/".join(f"{t}" for t in r2) + "°", "-",
                     " / ".join(f"{v:.2f}" for v in r2.values())))
    for mode, label in (("true_beta", "odometry with the true β"),
                        ("truth", "steering on the true pose and β")):
        pair = lim["path_following"][mode]
        swing = pair["feedback"].get("slip_angle_swing_deg")
        rest = (" the rest is the odometry's error" if mode == "true_beta" else
                f" rigid-ground gains, true β swings {swing:.0f}° a lap"
                if swing is not None else "")
        rows.append((f"limit: circle 15°, {label}: mean error Eq. 9 -> Eq. 10 [cm]", "-",
                     f"{100 * pair['feedback']['mean_error_m']:.1f} -> "
                     f"{100 * pair['feedforward']['mean_error_m']:.1f} "
                     f"(ratio {pair['feedforward_to_feedback_mean']:.2f};{rest})"))
    rows += oracle_rows(lim["path_following"].get("oracle_gain"))
    rows += [(f"target: {k}", "", "met" if v else "NOT met") for k, v in m["targets_met"].items()]
    return rows


ORACLE_LAWS = (("truth", "feedback", "Eq. 9 steering on the truth"),
               ("truth", "feedforward", "Eq. 10 steering on the truth"),
               ("observation", "feedback_gyrodometry", "Eq. 9 on gyrodometry"),
               ("observation", "feedforward_slip_compensated", "Eq. 10 on slip-compensated"))
"""The oracle gain's set-ups: (what the law steers on, the law's key, its label)."""


def oracle_rows(oracle: dict | None) -> list[tuple[str, str, str]]:
    """The ``limit:`` rows of each law's oracle gain (the best triple pole of the oracle grid
    on the laps' own true maximum error); none for a run without it."""
    if not oracle:
        return []
    poles = oracle["poles_rps"]
    rows = []
    for on, law, label in ORACLE_LAWS:
        g = oracle.get(on, {}).get(law)
        if g is None:
            continue
        rows.append((f"limit: circle 15°, oracle gain (best triple pole of {min(poles):g}-"
                     f"{max(poles):g} rad/s on the laps' max error), {label}", "-",
                     f"pole {g['pole_rps']:g} rad/s: mean {100 * g['mean_error_m']:.1f}, "
                     f"worst-lap max {100 * g['worst_max_error_m']:.1f} cm, "
                     f"{g['completed']}/{g['laps_run']} laps"))
    return rows


def format_table(result: dict) -> str:
    """Paper vs simulation as printed by the command, with a title line."""
    m = result["metrics"]
    rows = table_rows(result)
    w0 = max(len(r[0]) for r in rows)
    w1 = max(len(r[1]) for r in rows + [("", "paper")])
    lines = [f"Yamauchi et al. — paper vs simulation ({'quick' if result['quick'] else 'full'},"
             f" seed {result['seed']}, {m['run_time_s']:.0f} s)",
             f"{'':<{w0}}  {'paper':>{w1}}  simulation", "-" * (w0 + w1 + 40)]
    lines += [f"{a:<{w0}}  {b:>{w1}}  {c}" for a, b, c in rows]
    return "\n".join(lines)


def markdown_rows(result: dict) -> list[tuple[str, str, str]]:
    """:func:`table_rows` for a Markdown table (a variant row marked ``↳``)."""
    return [("↳ " + a.strip() if a.startswith("  ") else a, b, c)
            for a, b, c in table_rows(result)]
