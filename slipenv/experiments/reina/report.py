"""The paper-vs-simulation table of ``slipenv reproduce reina`` (Tables 4 and 5)."""

from __future__ import annotations

import math
from typing import SupportsFloat


def _f(x: SupportsFloat | None, digits: int = 3) -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "-"
    if isinstance(x, bool):
        return "yes" if x else "NO"
    if isinstance(x, int):
        return str(x)
    return f"{float(x):.{digits}g}"


def table_rows(result: dict) -> list[tuple[str, str, str]]:
    """(quantity, paper, simulation) rows."""
    m, p = result["metrics"], result["paper"]
    rows = []
    for t, label in (("sideways", "test 1, sideways climb"), ("mounds", "test 2, mounds")):
        rows.append((f"{label}: slip angle r.m.s. error E_beta [deg]",
                     _f(p["slip_angle_rms_deg"][t]), _f(m["slip_angle_rms_deg"][t])))
        rows.append((f"{label}: slip ratio r.m.s. error E_sx",
                     _f(p["slip_ratio_rms"][t]), _f(m["slip_ratio_rms"][t])))
        for k, name in (("plain", "plain"), ("compass", "compass-enhanced"), ("scomp", "sComp")):
            rows.append((f"{label}: final error, {name} odometry [m]",
                         _f(p["final_error_m"][t][k]), _f(m["final_error_m"][t][k])))
    ft, pf = m["ftrace"], p["ftrace"]
    rows.append(("FTrace frames", _f(pf["frames"]), _f(ft["frames"])))
    for k, name in (("false_positive", "false positives"), ("false_negative", "false negatives"),
                    ("misidentification", "misidentifications")):
        rows.append((f"FTrace {name} [%]", "< " + _f(100 * pf[k], 2), _f(100 * ft[k], 3)))
    return rows


def format_table(result: dict) -> str:
    """Plain-text table with the targets below it."""
    rows = table_rows(result)
    w = max(len(r[0]) for r in rows)
    lines = [f"Reina et al. re-run ({'quick' if result.get('quick') else 'full'}, seed "
             f"{result.get('seed')})", f"{'quantity':<{w}}  {'paper':>10}  {'simulation':>10}",
             "-" * (w + 24)]
    lines += [f"{q:<{w}}  {a:>10}  {b:>10}" for q, a, b in rows]
    lines.append("targets:")
    for key, value in result["metrics"]["targets_met"].items():
        lines.append(f"  {key}: {value}")
    return "\n".join(lines)
