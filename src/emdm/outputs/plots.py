"""Figures of runs: time series and workspace paths, overlaid for comparison (brief Task 1 and 2).

Every figure is one IEEE column wide (3.5 in), in the shared style (:mod:`emdm.style`), saved as
PNG, PDF and SVG. Controllers keep their colour and dash in every figure: EMDM blue (UC-EMDM indigo, so that
it prints darker than UC-IVKC's orange in greyscale), IVKC orange (C-IVKC vermilion),
constrained solid, unconstrained dashed.
"""

from __future__ import annotations

from collections.abc import Sequence
from enum import StrEnum
from pathlib import Path

import numpy as np
from matplotlib.patches import Circle

from ..core.arm import PlanarArm
from ..core.controllers import Name
from ..sim.loop import Run
from .animate import ellipse_points
from .style import COLUMN, CONTROLLER_STYLE, DOUBLE, color, figure
from .views import Views

GROUPS = {
    "UC": (Name.UC_IVKC, Name.UC_EMDM),
    "C": (Name.C_IVKC, Name.C_EMDM),
    "all": (Name.UC_IVKC, Name.C_IVKC, Name.UC_EMDM, Name.C_EMDM),
    "baselines": (Name.RRMC, Name.PARK, Name.MMC, Name.C_EMDM),
}
"""The overlays the brief asks for, all four together, and the manipulability benchmark's
baselines beside C-EMDM."""


class Quantity(StrEnum):
    """The scalar quantities :func:`series_figure` draws against time."""

    EFFORT = "effort"
    MANIPULABILITY = "manipulability"
    MANIP_RATE = "manip_rate"
    ERROR = "error"
    ALPHA = "alpha"
    SLACK = "slack"
    CLEARANCE = "clearance"


class Joints(StrEnum):
    """What :func:`joints_figure` draws per joint: velocities or positions."""

    VELOCITIES = "qd"
    POSITIONS = "q"


LABELS = {
    Quantity.EFFORT: "effort E (rad^2/s^2)",
    Quantity.MANIPULABILITY: "manipulability m",
    Quantity.MANIP_RATE: "manipulability rate M (1/s)",
    Quantity.ERROR: "tracking error ||e|| (m)",
    Quantity.ALPHA: "task scale alpha",
    Quantity.SLACK: "task slack ||delta|| (m/s)",
    Quantity.CLEARANCE: "clearance to obstacles (m)",
}
"""The y-axis label of each quantity."""


def _style(run: Run, index: int) -> dict[str, object]:
    base = CONTROLLER_STYLE.get(run.controller.name, {"color": color(index), "linestyle": "-"})
    return {**base, "label": run.controller.name}


def _title(runs: Sequence[Run]) -> str:
    return f"{runs[0].scenario.name}: " + " vs ".join(r.controller.name for r in runs)


def _command_time(run: Run) -> np.ndarray:
    return run.t[:-1]


def series_figure(runs: Sequence[Run], quantity: Quantity, stem: Path) -> Path:
    """One scalar quantity against time, overlaid for ``runs``.

    ``quantity``: effort (E, rad^2/s^2, log scale), manipulability (m), manipulability rate
    (M, 1/s), error (||e||, m, log scale), alpha (task scale) or slack (||delta||, m/s).
    """
    quantity = Quantity(quantity)
    with figure(stem, width=COLUMN, height=2.0) as (_, ax):
        for i, run in enumerate(runs):
            style = _style(run, i)
            if quantity is Quantity.MANIPULABILITY:
                ax.plot(run.t, run.m, **style)
            elif quantity is Quantity.CLEARANCE:
                ax.plot(run.t, run.clearance, **style)
            elif quantity is Quantity.ERROR:
                ax.semilogy(run.t, np.maximum(run.error_norm, 1e-6), **style)
            else:
                values = {
                    Quantity.EFFORT: run.effort,
                    Quantity.MANIP_RATE: run.manip_rate,
                    Quantity.ALPHA: run.alpha,
                    Quantity.SLACK: np.linalg.norm(run.delta, axis=1),
                }[quantity]
                ax.step(_command_time(run), values, where="post", **style)
        if quantity is Quantity.EFFORT:
            ax.set_yscale("log")  # spans many decades: the UC start spikes, the goal tends to 0
        if quantity is Quantity.ERROR:
            ax.axhline(
                runs[0].scenario.motion.tolerance,
                color="grey",
                linestyle=":",
                linewidth=0.8,
                label="tolerance",
            )
        if quantity is Quantity.ALPHA:
            ax.set_ylim(-0.05, 1.05)
        if quantity is Quantity.CLEARANCE:
            od = runs[0].scenario.obstacle_damper
            for value, text, dash in ((od.stop, "stop", "-"), (od.influence, "influence", ":")):
                ax.axhline(value, color="grey", linestyle=dash, linewidth=0.8, label=text)
        ax.set_xlabel("time t (s)")
        label = LABELS[quantity]
        if runs[0].e.shape[1] == 6:  # a pose: the error and slack rows mix metres and radians
            label = label.replace("(m)", "(m and rad)").replace("(m/s)", "(m/s and rad/s)")
        ax.set_ylabel(label)
        ax.set_title(_title(runs))
        ax.legend()
    return stem


def joints_figure(runs: Sequence[Run], kind: Joints, stem: Path) -> Path:
    """Joint velocities (``kind="qd"``) with their limits, or joint positions (``"q"``) with the
    limits and the dampers' influence (light) and stop (dark) zones shaded; one panel per joint."""
    kind = Joints(kind)
    sc = runs[0].scenario
    n = sc.n
    with figure(stem, width=COLUMN, height=0.95 * n + 0.5, nrows=n, sharex=True, squeeze=False) as (
        _,
        axes,
    ):
        for j in range(n):
            ax = axes[j, 0]
            if kind is Joints.VELOCITIES:
                for i, run in enumerate(runs):
                    ax.step(_command_time(run), run.qd[:, j], where="post", **_style(run, i))
                for bound in (sc.arm.qd_min[j], sc.arm.qd_max[j]):
                    ax.axhline(bound, color="black", linewidth=0.7, linestyle=":")
                ax.set_ylabel(f"qd{j + 1} (rad/s)")
            else:
                for i, run in enumerate(runs):
                    ax.plot(run.t, run.q[:, j], **_style(run, i))
                lo, hi = sc.arm.q_min[j], sc.arm.q_max[j]
                infl, stop = sc.damper.influence[j], sc.damper.stop[j]
                ax.axhspan(hi - infl, hi, color="grey", alpha=0.12, linewidth=0)
                ax.axhspan(lo, lo + infl, color="grey", alpha=0.12, linewidth=0)
                ax.axhspan(hi - stop, hi, color="grey", alpha=0.35, linewidth=0)
                ax.axhspan(lo, lo + stop, color="grey", alpha=0.35, linewidth=0)
                for bound in (lo, hi):
                    ax.axhline(bound, color="black", linewidth=0.7)
                ax.set_ylabel(f"q{j + 1} (rad)")
        axes[-1, 0].set_xlabel("time t (s)")
        what = (
            "joint velocities and limits"
            if kind is Joints.VELOCITIES
            else "joint positions, influence zones"
        )
        axes[0, 0].set_title(f"{_title(runs)}\n{what}")
        axes[0, 0].legend(ncols=2)
    return stem


def spatial_path_figure(runs: Sequence[Run], stem: Path) -> Path:
    """End-effector paths of a spatial arm in three orthogonal projections, with the arm at the
    start, its translational manipulability ellipsoid there, and the goal."""
    sc = runs[0].scenario
    views = Views(sc)
    box = views.limits(runs)
    q0 = np.asarray(sc.motion.q0)
    start = views.joints(q0)
    J = views.jacobian(q0)
    size = 0.5 * float((box[:, 1] - box[:, 0]).max())
    scale = 0.3 * size / float(np.sqrt(np.linalg.eigvalsh(J @ J.T)[-1]))
    with figure(stem, width=DOUBLE, height=2.6, ncols=3) as (fig, axes):
        for v, (ax, P) in enumerate(zip(axes, views.projections, strict=True)):
            for i, run in enumerate(runs):
                path = views.position(run) @ P.T
                ax.plot(path[:, 0], path[:, 1], **_style(run, i))
            pts = start @ P.T
            views.draw_obstacles(ax, P)
            ax.fill(*ellipse_points(P @ J, P @ start[-1], scale).T, color="grey", alpha=0.2)
            ax.plot(
                pts[:, 0],
                pts[:, 1],
                color="black",
                linewidth=1.2,
                marker="o",
                markersize=2.5,
                label="arm at start",
            )
            goal = P @ np.asarray(sc.motion.goal[:3])
            ax.plot(*goal, marker="*", color="black", markersize=9, linestyle="none", label="goal")
            ax.set_xlim(*(P @ box)[0])
            ax.set_ylim(*(P @ box)[1])
            ax.set_aspect("equal")
            ax.set_xlabel(f"{views.axes[v][0]} (m)")
            ax.set_ylabel(f"{views.axes[v][1]} (m)")
            ax.set_title(views.names[v])
        fig.suptitle(
            f"{_title(runs)}: end-effector path\n(grey: the translational manipulability "
            f"ellipsoid at the start, x{scale:.2g} m/s per rad/s)",
            fontsize=8,
        )
        fig.legend(
            *axes[0].get_legend_handles_labels(), loc="outside lower center", ncols=6, fontsize=6
        )
    return stem


def path_figure(runs: Sequence[Run], stem: Path) -> Path:
    """End-effector paths in the workspace, with start, goal and the reachable annulus."""
    sc = runs[0].scenario
    arm = sc.robot
    if not isinstance(arm, PlanarArm):  # a view of each plane of the workspace
        return spatial_path_figure(runs, stem)
    with figure(stem, width=COLUMN, height=3.0) as (_, ax):
        ax.add_patch(
            Circle((0, 0), arm.reach, color="grey", alpha=0.10, linewidth=0, label="reachable")
        )
        if arm.inner_reach > 0:
            ax.add_patch(Circle((0, 0), arm.inner_reach, color="white", linewidth=0))
        Views(sc).draw_obstacles(ax, np.eye(2))
        for i, run in enumerate(runs):
            ax.plot(run.p[:, 0], run.p[:, 1], **_style(run, i))
        start = arm.joint_positions(sc.motion.q0)
        ax.plot(
            start[:, 0],
            start[:, 1],
            color="black",
            linewidth=1.5,
            marker="o",
            markersize=3,
            label="arm at start",
        )
        ax.plot(
            *sc.motion.goal, marker="*", color="black", markersize=9, linestyle="none", label="goal"
        )
        ax.set_aspect("equal")
        ax.set_xlim(-arm.reach * 1.05, arm.reach * 1.05)
        ax.set_ylim(-arm.reach * 1.05, arm.reach * 1.05)
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.set_title(f"{_title(runs)}: end-effector path")
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), ncols=3, fontsize=6)
    return stem


def run_figures(runs: dict[str, Run], out: Path) -> list[Path]:
    """Every run figure for every group of the available controllers (or, when no group fits,
    for all the runs together, in ``runs/``); returns the stems."""
    stems: list[Path] = []
    groups = [(g, [runs[n] for n in names if n in runs]) for g, names in GROUPS.items()]
    groups = [
        (g, chosen)
        for g, chosen in groups
        if chosen
        and not (g == "all" and len(chosen) < 3)
        and not (g == "baselines" and len(chosen) < 2)
    ]
    if not groups:  # runs that no overlay of the brief or the benchmark gathers: all together
        groups = [("runs", list(runs.values()))]
    for group, chosen in groups:
        folder = out / group
        for quantity in Quantity:
            if quantity is Quantity.SLACK and not any(np.any(r.delta != 0) for r in chosen):
                continue
            if quantity is Quantity.ALPHA and all(np.all(r.alpha == 1.0) for r in chosen):
                continue
            if quantity is Quantity.CLEARANCE and not chosen[0].scenario.obstacles:
                continue
            stems.append(series_figure(chosen, quantity, folder / quantity))
        stems.append(joints_figure(chosen, Joints.VELOCITIES, folder / "joint_velocities"))
        stems.append(joints_figure(chosen, Joints.POSITIONS, folder / "joint_positions"))
        stems.append(path_figure(chosen, folder / "path"))
    return stems
