"""The paper-vs-simulation table of ``slipenv reproduce lindgren`` and its targets.

The table has one column per block: the headline (the curved Janosi/Okello world the filter
does not assume) and the ablation (the world with the filter's own linear law). "no_slip_model"
is scheme 3 (all sensors, no slip model), "slip_model" the block's best slip-model scheme.

:func:`table_rows` is the one source of the table; :func:`format_table` prints it,
:func:`markdown_rows` feeds the results page (:mod:`.docs`).
"""

from __future__ import annotations

from ..results import finite, write_json

__all__ = ["finite", "format_table", "markdown_rows", "nis_distance", "table_rows", "targets",
           "write_json"]


def nis_distance(value: float | None, band: list) -> float | None:
    """How far a time-averaged NIS lies outside its band (0 inside); None without a NIS (every
    odometry update of the window rejected) or a band."""
    if value is None or band[0] is None:
        return None
    return max(band[0] - value, value - band[1], 0.0)


def targets(m: dict) -> dict[str, dict]:
    """A block's targets, each with its value, limit and whether the run met it.

    ``m`` is one block's metrics (``no_slip_model`` / ``slip_model`` keys in its
    ``mean_deviation_m``, ``deviation_from_scheme1_m``, ``nis`` and
    ``dropout_final_error_m``). "NIS in the band" has the distance outside the band as value
    and 0 as limit. The circles' target is judged on the mean error against the truth; the
    same ratio on the paper's measure, the deviation from scheme 1 (Table 1: the paper had no
    ground truth), is kept beside it.
    """
    dev, nis_, drop = m["mean_deviation_m"], m["nis"], m["dropout_final_error_m"]
    dev1 = m["deviation_from_scheme1_m"]
    slip_nis = nis_distance(nis_["slip_model"], nis_["band"])
    rows = {
        "slip_model mean error <= 0.7 no_slip_model": (dev["slip_model"],
                                                       0.7 * dev["no_slip_model"]),
        "slip_model deviation from scheme 1 <= 0.7 no_slip_model": (
            dev1["slip_model"], 0.7 * dev1["no_slip_model"]),
        "slip_model NIS inside the 95 % band": (slip_nis, 0.0),
        "slip_model NIS closer to band than no_slip_model": (
            slip_nis, nis_distance(nis_["no_slip_model"], nis_["band"])),
        "slip_model <= 0.3 no_slip_model": (drop["slip_model"], 0.3 * drop["no_slip_model"]),
        "slip_model <= 1.5 oracle": (drop["slip_model"], 1.5 * drop["oracle"]),
    }
    return {k: {"value": v, "limit": lim,
                "met": v is not None and lim is not None and bool(v <= lim if "<=" in k
                                                                  or "inside" in k
                                                                  else v < lim)}
            for k, (v, lim) in rows.items()}


# Variants of (b): (variant, the scheme it varies, what it changes)
DROPOUT_VARIANT_ROWS = (
    ("scheme3_gated", "scheme3", "with the estimator's χ² bearing gate"),
    ("scheme3_one_radius", "scheme3", "with one measured radius for both wheels"),
    ("scheme3_nominal_radius", "scheme3", "with the nominal (concrete) radius"),
    ("scheme4_field_soil_noise", "scheme4", "with the uniform-field soil random walk"),
    ("scheme4_no_lateral", "scheme4", "without the lateral slip gain (the paper's state)"),
    ("oracle_lateral", "oracle", "with the lateral slip gain"),
    ("oracle_secant", "oracle", "given the secant k_s of the calibration drive"),
    ("scheme4_cut_x2", "scheme4", "with the laser cut at twice the time"),
    ("oracle_cut_x2", "oracle", "with the laser cut at twice the time"),
)


def table_rows(m: dict, paper: dict) -> list[tuple]:
    """(quantity, paper, headline, ablation) for Tables 1-3 and Fig. 7; one-element rows are
    headings.

    ``m`` is the experiment's ``metrics`` (``{"headline": ..., "ablation": ...}``), ``paper``
    its ``PAPER`` dict (scheme 3 and 4 there are the paper's no-slip and slip model); rows the
    paper has no number for (the true errors, NEES, the oracle, the variants, a scheme beyond
    the paper's) have None as paper value, and a block without a row's value None.
    """
    blocks = [m.get("headline"), m.get("ablation")]

    def each(get) -> list:
        out = []
        for b in blocks:
            try:
                value = None if b is None else get(b)
            except KeyError:
                value = None
            out.append(value)
        return out

    head = m["headline"]
    d = head["dropout"]
    schemes = sorted({s for b in blocks if b for s in b["slip_model_schemes_final_error_m"]})
    rows: list[tuple] = [("(a) 4 m circles, clockwise arc at constant speed",),
                         ("slip model: the best slip-model scheme after the cut", "scheme 4",
                          *each(lambda b: b["slip_model_scheme"]))]
    # the judged measure (against the truth: the paper had none) first, then the paper's own
    # (against scheme 1), each with its paper value where the paper has one
    for metric, label, paper_values in (
            ("mean_deviation_m", "mean error against the truth [m]", dict[str, float]()),
            ("deviation_from_scheme1_m", "deviation from scheme 1 [m] (the paper's Table 1)",
             paper["mean_deviation_m"])):
        for key, alias in (("no_slip_model", "no_slip_model (scheme3)"),
                           ("slip_model", "slip_model")):
            rows.append((f"{label}, {alias}", paper_values.get(_PAPER_SCHEME[key]),
                         *each(lambda b, m_=metric, k=key: b[m_][k])))
        if len(schemes) > 1:
            for s in schemes:
                rows.append((f"  {s}", None, *each(lambda b, m_=metric, s=s: b[m_][s])))
        rows.append(("  no_slip_model with the estimator's χ² bearing gate", None,
                     *each(lambda b, m_=metric: b["circles"][m_]["scheme3_gated"])))
        rows.append(("  scheme4 without the lateral slip gain (the paper's state)", None,
                     *each(lambda b, m_=metric: b["circles"][m_]["scheme4_no_lateral"])))
    for s in ("scheme1", "scheme3", *schemes, "scheme4_no_lateral", "oracle", "oracle_lateral"):
        rows.append((f"  mean error against the truth [m] / pose NEES, {s}", None,
                     *each(lambda b, s=s: f"{b['circles']['mean_deviation_m'][s]:.3f} / "
                                          f"{b['circles']['nees_pose'][s]:.2f}")))
    for key, label in (("nis", "NIS, Eq. 43"), ("autocorr_mean", "autocorrelation mean"),
                       ("autocorr_var", "autocorrelation variance"),
                       ("autocorr_share_inside", "share inside ±1.96/√K")):
        for alias in ("no_slip_model", "slip_model"):
            rows.append((f"{label}, {alias}", paper[key][_PAPER_SCHEME[alias]],
                         *each(lambda b, k=key, a=alias: b[k][a])))
    rows.append(("NIS 95 % band: exact (Eq. 44)", "1.883-2.120",
                 *each(lambda b: "{:.3f}-{:.3f} ({:.3f}-{:.3f})".format(
                     *b["nis"]["band"], *b["nis"]["band_wilson_hilferty"])
                     if b["nis"]["band"][0] is not None else None)))
    rows.append(("K, odometric innovations in the window", paper["n_samples"],
                 *each(lambda b: b["n_samples"]["slip_model"])))
    rows.append((f"(b) straights, laser + odometry, laser cut at {d['cut_s']:.0f} s, mean of "
                 f"{len(d['seeds'])} drives",))
    for key in ("no_slip_model", "slip_model", "oracle"):
        rows.append((f"final position error [m], {key}", paper["dropout_final_error_m"][key],
                     *each(lambda b, k=key: b["dropout_final_error_m"][k])))
    if len(schemes) > 1:
        for s in schemes:
            rows.append((f"  {s}", None,
                         *each(lambda b, s=s: b["slip_model_schemes_final_error_m"][s])))
    for s in ("scheme3", *schemes, "oracle"):
        rows.append((f"  pose NEES after the cut (n = 3), {s}", None,
                     *each(lambda b, s=s: b["dropout"]["nees_after_cut"][s])))
    rows.append(("  its 95 % band if the samples were independent", None,
                 *each(lambda b: "{:.2f}-{:.2f}".format(
                     *b["dropout"]["nees_after_cut_band_if_independent"]))))
    for variant, base, what in DROPOUT_VARIANT_ROWS:
        values = each(lambda b, v=variant: b["dropout"]["final_error_m"][v])
        if any(v is not None for v in values):
            rows.append((f"  {base} {what}", None, *values))
    return rows


_PAPER_SCHEME = {"no_slip_model": "scheme3", "slip_model": "scheme4"}


def cell(v) -> str:
    """A table cell: ``-`` for no value, 4 significant digits for a float."""
    return "-" if v is None else (f"{v:.4g}" if isinstance(v, float) else str(v))


def target_lines(tg: dict) -> list[str]:
    """One ``[met]``/``[MISSED]`` line per target: value against limit."""
    return [f"[{'met' if t['met'] else 'MISSED'}] {k}: {_g(t['value'])} vs {_g(t['limit'])}"
            for k, t in tg.items()]


def _g(value: float | None) -> str:
    return "n/a" if value is None else f"{value:.4g}"


def format_table(m: dict, paper: dict, tg: dict, run_time_s: float) -> str:
    """Quantity | paper | headline | ablation for Tables 1-3 and Fig. 7, then each block's
    targets (``tg``: ``{"headline": targets, "ablation": targets}``)."""
    rows = table_rows(m, paper)
    width = max(len(r[0]) for r in rows)
    lines = [f"{'quantity':<{width}}  {'paper':>12}  {'headline':>22}  {'ablation':>22}",
             "-" * (width + 62)]
    lines += [r[0] if len(r) == 1 else
              f"{r[0]:<{width}}  {cell(r[1]):>12}  {cell(r[2]):>22}  {cell(r[3]):>22}"
              for r in rows]
    for name, targets_ in tg.items():
        lines.append(f"targets, {name} ({m[name]['world']}):")
        lines += ["  " + line for line in target_lines(targets_)]
    lines.append(f"run time {run_time_s:.1f} s")
    return "\n".join(lines)


def markdown_rows(m: dict, paper: dict) -> list[tuple]:
    """:func:`table_rows` with formatted cells, for a Markdown table."""
    def label(text: str) -> str:  # an indented row is a variant of the row above
        return "↳ " + text.strip() if text.startswith("  ") else text

    return [r if len(r) == 1 else (label(r[0]), *(cell(v) for v in r[1:]))
            for r in table_rows(m, paper)]
