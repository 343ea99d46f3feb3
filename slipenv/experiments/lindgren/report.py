"""The paper-vs-simulation table of ``slipenv reproduce lindgren`` and its targets.

The table has one column per block: the headline (the world with the filter's own linear law)
and the robust block (the curved Janosi/Okello world).

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
    """The reproduction's targets, each with its value, limit and whether the run met it."""
    dev, nis_, drop = m["mean_deviation_m"], m["nis"], m["dropout_final_error_m"]
    rows = {
        "slip_model <= 0.3 no_slip_model": (drop["slip_model"], 0.3 * drop["no_slip_model"]),
        "scheme4 deviation <= 0.7 scheme3": (dev["scheme4"], 0.7 * dev["scheme3"]),
        "scheme4 NIS closer to band than scheme3": (nis_distance(nis_["scheme4"], nis_["band"]),
                                                    nis_distance(nis_["scheme3"], nis_["band"])),
        "slip_model <= 1.5 oracle": (drop["slip_model"], 1.5 * drop["oracle"]),
    }
    return {k: {"value": v, "limit": lim,
                "met": v is not None and lim is not None and bool(v <= lim if "<=" in k
                                                                  else v < lim)}
            for k, (v, lim) in rows.items()}


# Variants of (b): (variant, the scheme it varies, what it changes)
DROPOUT_VARIANT_ROWS = (
    ("scheme3_gated", "scheme3", "with the estimator's χ² bearing gate"),
    ("scheme3_nominal_radius", "scheme3", "with the nominal (concrete) radius"),
    ("scheme4_default_soil_noise", "scheme4", "with the estimator's soil random walk"),
    ("scheme4_field_soil_noise", "scheme4", "with the uniform-field soil random walk"),
    ("oracle_secant", "oracle", "given the secant k_s of the calibration drive"),
    ("scheme4_cut_x2", "scheme4", "with the laser cut at twice the time"),
    ("oracle_cut_x2", "oracle", "with the laser cut at twice the time"),
)
_DROPOUT_KEYS = {"scheme3": "no_slip_model", "scheme4": "slip_model", "oracle": "oracle"}


def table_rows(m: dict, paper: dict) -> list[tuple]:
    """(quantity, paper, headline, robust) for Tables 1-3 and Fig. 7; one-element rows are
    headings.

    ``m`` is the experiment's ``metrics`` (the robust block in ``m["robust"]``, if run),
    ``paper`` its ``PAPER`` dict; rows the paper has no number for (the true errors, NEES, the
    oracle, the variants) have None as paper value, and a block without a row's variant None
    as its value.
    """
    blocks = [m, m.get("robust")]

    def each(get) -> list:
        out = []
        for b in blocks:
            try:
                out.append(None if b is None else get(b))
            except KeyError:
                out.append(None)
        return out

    d = m["dropout"]
    rows: list[tuple] = [("(a) 4 m circles, clockwise arc at constant speed",)]
    for s in ("scheme3", "scheme4"):
        rows.append((f"mean deviation from scheme 1 [m], {s}", paper["mean_deviation_m"][s],
                     *each(lambda b, s=s: b["mean_deviation_m"][s])))
    rows.append(("  scheme3 with the estimator's χ² bearing gate", None,
                 *each(lambda b: b["circles"]["mean_deviation_m"]["scheme3_gated"])))
    for s in ("scheme3", "scheme4", "oracle"):
        rows.append((f"  true mean error [m] / pose NEES, {s}", None,
                     *each(lambda b, s=s: f"{b['circles']['true_error_mean_m'][s]:.3f} / "
                                          f"{b['circles']['nees_pose'][s]:.2f}")))
    for key, label in (("nis", "NIS, Eq. 43"), ("autocorr_mean", "autocorrelation mean"),
                       ("autocorr_var", "autocorrelation variance"),
                       ("autocorr_share_inside", "share inside ±1.96/√K")):
        for s in ("scheme3", "scheme4"):
            rows.append((f"{label}, {s}", paper[key][s], *each(lambda b, k=key, s=s: b[k][s])))
    rows.append(("NIS 95 % band: exact (Eq. 44)", "1.883-2.120",
                 *each(lambda b: "{:.3f}-{:.3f} ({:.3f}-{:.3f})".format(
                     *b["nis"]["band"], *b["nis"]["band_wilson_hilferty"])
                     if b["nis"]["band"][0] is not None else None)))
    rows.append(("K, odometric innovations in the window", paper["n_samples"],
                 *each(lambda b: b["n_samples"]["scheme4"])))
    rows.append((f"(b) straights, laser + odometry, laser cut at {d['cut_s']:.0f} s, mean of "
                 f"{len(d['seeds'])} drives",))
    for key in ("no_slip_model", "slip_model", "oracle"):
        rows.append((f"final position error [m], {key}", paper["dropout_final_error_m"][key],
                     *each(lambda b, k=key: b["dropout_final_error_m"][k])))
    for variant, base, what in DROPOUT_VARIANT_ROWS:
        values = each(lambda b, v=variant: b["dropout"]["final_error_m"][v])
        if any(v is not None for v in values):
            rows.append((f"  {_DROPOUT_KEYS[base]} {what}", None, *values))
    return rows


def cell(v) -> str:
    """A table cell: ``-`` for no value, 4 significant digits for a float."""
    return "-" if v is None else (f"{v:.4g}" if isinstance(v, float) else str(v))


def target_lines(tg: dict) -> list[str]:
    """One ``[met]``/``[MISSED]`` line per target: value against limit."""
    return [f"[{'met' if t['met'] else 'MISSED'}] {k}: {_g(t['value'])} vs {_g(t['limit'])}"
            for k, t in tg.items()]


def _g(value: float | None) -> str:
    return "n/a" if value is None else f"{value:.4g}"


def format_table(m: dict, paper: dict, tg: dict, run_time_s: float,
                 tg_robust: dict | None = None) -> str:
    """Quantity | paper | headline | robust for Tables 1-3 and Fig. 7, then the targets for
    each block."""
    rows = table_rows(m, paper)
    width = max(len(r[0]) for r in rows)
    lines = [f"{'quantity':<{width}}  {'paper':>12}  {'headline':>22}  {'robust':>22}",
             "-" * (width + 62)]
    lines += [r[0] if len(r) == 1 else
              f"{r[0]:<{width}}  {cell(r[1]):>12}  {cell(r[2]):>22}  {cell(r[3]):>22}"
              for r in rows]
    for name, targets_ in (("headline", tg), ("robust", tg_robust)):
        if targets_ is not None:
            lines.append(f"targets, {name}:")
            lines += ["  " + line for line in target_lines(targets_)]
    lines.append(f"run time {run_time_s:.1f} s")
    return "\n".join(lines)


def markdown_rows(m: dict, paper: dict) -> list[tuple]:
    """:func:`table_rows` with formatted cells, for a Markdown table."""
    def label(text: str) -> str:  # an indented row is a variant of the row above
        return "↳ " + text.strip() if text.startswith("  ") else text

    return [r if len(r) == 1 else (label(r[0]), *(cell(v) for v in r[1:]))
            for r in table_rows(m, paper)]
