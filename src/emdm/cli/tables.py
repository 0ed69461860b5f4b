"""The tables the commands print: one row per controller, or per solver."""

from __future__ import annotations

from typing import Any


def _table(rows: list[list[str]], header: list[str]) -> str:
    widths = [max(len(str(r[i])) for r in [header, *rows]) for i in range(len(header))]
    line = "  ".join(h.ljust(w) for h, w in zip(header, widths, strict=True))
    body = [
        "  ".join(
            str(c).rjust(w) if i else str(c).ljust(w)
            for i, (c, w) in enumerate(zip(r, widths, strict=True))
        )
        for r in rows
    ]
    return "\n".join([line, "-" * len(line), *body])


def summary_table(results: dict[str, dict[str, Any]], error_unit: str = "m") -> str:
    """A readable table of the main metrics, one row per controller (``error_unit``: "m", or
    "m,rad" for a pose task)."""
    rows = []
    clearance = any("min_clearance" in mt for mt in results.values())
    for name, mt in results.items():
        ttg = mt["time_to_goal"]
        rows.append(
            [
                name,
                f"stopped@{mt['stopped']['step']}"
                if mt.get("stopped")
                else ("yes" if mt["reached"] else "no"),
                str(mt["steps"]),
                f"{ttg:.2f}" if ttg is not None else "-",
                f"{mt['final_error']:.2e}",
                f"{mt['min_manipulability']:.4f}",
                f"{mt['mean_manipulability']:.4f}",
                f"{mt['total_effort']:.4f}",
                f"{mt['max_abs_qd']:.3f}",
                f"{mt['min_joint_margin']:.3f}",
                str(mt["scaled_steps"]),
                str(mt["fallback_steps"]),
                f"{mt['max_kkt_residual']:.1e}",
            ]
            + ([f"{mt['min_clearance']:.4f}"] if clearance else [])
        )
    header = [
        "controller",
        "reached",
        "steps",
        "t_goal[s]",
        f"final|e|[{error_unit}]",
        "min m",
        "mean m",
        "effort",
        "max|qd|",
        "margin[rad]",
        "scaled",
        "fallback",
        "max KKT",
    ] + (["clearance[m]"] if clearance else [])
    return _table(rows, header)


def lab_table(summary: dict[str, dict[str, Any]]) -> str:
    """The solver comparison as a readable table."""
    rows = []
    for name, s in summary.items():
        ttg = s.get("time_to_goal")
        rows.append(
            [
                name,
                s["family"],
                f"{s['median_time'] * 1e3:.3f}",
                f"{s['p95_time'] * 1e3:.3f}",
                f"{s['median_iterations']:.0f}",
                f"{s['median_evaluations']:.0f}",
                f"{s['max_abs_gap']:.1e}",
                f"{s['max_violation']:.1e}",
                str(s["failures"]),
                "yes" if s.get("reached") else "no",
                f"{ttg:.2f}" if ttg is not None else "-",
            ]
        )
    header = [
        "solver",
        "family",
        "median[ms]",
        "p95[ms]",
        "iters",
        "evals",
        "max|gap|",
        "max viol",
        "failed",
        "reached",
        "t_goal[s]",
    ]
    return _table(rows, header)
