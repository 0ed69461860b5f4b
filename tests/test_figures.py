"""Figures, animations and Pareto fronts: checked against the mathematics and read back."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest
from PIL import Image

import emdm
from emdm.cli import main
from emdm.core.controllers import program_at
from emdm.outputs.animate import Animator, animate, ellipse_points, frame_schedule
from emdm.outputs.plots import path_figure, run_figures
from emdm.outputs.records import read_run
from emdm.outputs.style import formats
from emdm.studies.pareto import front_at, pareto_steps, pareto_study, ratios


@pytest.fixture(scope="module")
def task2_runs():
    sc = emdm.load_scenario("task2", {"motion.max_time": 4.0})
    return {c: emdm.simulate(sc, c) for c in emdm.CONTROLLERS}


@pytest.fixture
def drawn(monkeypatch):
    """The figures :mod:`emdm.outputs.paper_figures` draws during a test, kept to be looked at
    (they are closed once saved)."""
    from emdm.outputs import paper_figures as pf

    made = []

    class Kept(pf.Figure):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            made.append(self)

    monkeypatch.setattr(pf, "Figure", Kept)
    return made


def test_read_run_is_exact(tmp_path):
    assert main(["run", "task1", "--out", str(tmp_path)]) == 0
    sc = emdm.load_scenario("task1")
    for name in emdm.CONTROLLERS:
        again, run = read_run(tmp_path, name), emdm.simulate(sc, name)
        for field in (
            "t",
            "q",
            "p",
            "e",
            "v",
            "m",
            "qd",
            "effort",
            "manip_rate",
            "alpha",
            "delta",
            "lo",
            "hi",
            "active",
            "kkt",
            "bound_excess",
            "fallback",
            "iterations",
        ):
            assert np.array_equal(getattr(again, field), getattr(run, field)), (name, field)
        assert again.reached == run.reached and again.solver == run.solver


@pytest.mark.slow  # 26 figures
def test_run_figures_cover_every_group_in_three_formats(tmp_path, task2_runs):
    # every figure as PNG (its size is checked below); PDF and SVG on one of them
    with formats((".png",)):
        stems = run_figures(task2_runs, tmp_path)
    vector = path_figure(list(task2_runs.values()), tmp_path / "vector" / "path")
    for suffix in (".png", ".pdf", ".svg"):
        assert vector.with_suffix(suffix).stat().st_size > 2000
    names = {(s.parent.name, s.name) for s in stems}
    for group in ("UC", "C", "all"):
        for figure_name in (
            "effort",
            "manipulability",
            "manip_rate",
            "error",
            "joint_velocities",
            "joint_positions",
            "path",
        ):
            assert (group, figure_name) in names
    assert ("C", "slack") in names  # the non-redundant EMDM uses its slack
    for stem in stems:
        assert stem.with_suffix(".png").stat().st_size > 2000
        with Image.open(stem.with_suffix(".png")) as image:
            width_in = image.size[0] / 200  # saved at 200 dpi
            assert width_in == pytest.approx(3.5, abs=0.01), stem  # one IEEE column


def test_plot_command_from_a_run_folder_and_bad_folders(tmp_path, capsys):
    run_dir = tmp_path / "run"
    assert (
        main(
            [
                "run",
                "task2",
                "--controller",
                "C-EMDM",
                "--controller",
                "C-IVKC",
                "--set",
                "motion.max_time=2",
                "--out",
                str(run_dir),
            ]
        )
        == 0
    )
    with formats((".png",)):  # the formats are checked above; here what is drawn
        assert main(["plot", str(run_dir), "--out", str(tmp_path / "figs")]) == 0
    assert (tmp_path / "figs" / "C" / "path.png").exists()
    assert not (tmp_path / "figs" / "UC").exists()  # only what was run
    capsys.readouterr()
    empty = tmp_path / "empty"
    empty.mkdir()
    assert main(["plot", str(empty), "--out", str(tmp_path / "x")]) == 2
    assert "not a run folder" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


# ---------------------------------------------------------------------------------- animations
def test_frame_schedule_is_true_to_dt():
    indices, stride = frame_schedule(100, 0.05, 1.0, 20.0)
    assert stride == 1 and indices == list(range(101))
    # at 4x, one step lasts 12.5 ms: too fast and not whole centiseconds; 4 steps make 50 ms
    indices, stride = frame_schedule(100, 0.05, 4.0, 20.0)
    assert stride == 4 and stride * 0.05 / 4.0 == pytest.approx(0.05)
    assert indices[-1] == 100
    indices, stride = frame_schedule(10, 0.03, 1.0, 40.0)  # 30 ms frames, 33 fps <= 40
    assert stride == 1
    assert frame_schedule(10, 0.03, 1.0, 30.0)[1] == 2  # 33 fps > 30: every other state


@pytest.mark.parametrize("speedup", [1.0, 2.0])
def test_gif_read_back_matches_the_run(tmp_path, speedup):
    sc = emdm.load_scenario("task2", {"motion.max_time": 1.5})  # 30 steps: 31 frames at 1x
    runs = [emdm.simulate(sc, "C-IVKC"), emdm.simulate(sc, "C-EMDM")]
    written = animate(runs, tmp_path / "anim", speedup=speedup, mp4=False)
    steps = max(r.steps for r in runs)
    dt = runs[0].scenario.motion.dt
    indices, _ = frame_schedule(steps, dt, speedup, 20.0)
    with Image.open(written[0]) as gif:
        assert gif.n_frames == len(indices)
        durations = []
        for i in range(gif.n_frames):
            gif.seek(i)
            durations.append(gif.info["duration"])
    expected = [round((b - a) * dt / speedup * 1000) for a, b in itertools.pairwise(indices)]
    assert durations[:-1] == expected
    assert durations[-1] == 1000  # the final state is held for a second
    assert sum(durations[:-1]) == pytest.approx(steps * dt / speedup * 1000, abs=1)


def test_the_gif_and_the_mp4_share_frames_drawn_once(tmp_path, monkeypatch):
    pytest.importorskip("imageio_ffmpeg")
    sc = emdm.load_scenario("task2", {"motion.max_time": 0.5})
    runs = [emdm.simulate(sc, "C-IVKC"), emdm.simulate(sc, "C-EMDM")]
    drawn: list[int] = []
    draw = Animator.draw
    monkeypatch.setattr(Animator, "draw", lambda self, i: drawn.append(i) or draw(self, i))
    written = animate(runs, tmp_path / "anim")
    assert [p.suffix for p in written] == [".gif", ".mp4"]
    assert drawn == list(range(len(frame_schedule(10, 0.05, 1.0, 20.0)[0])))


def test_ellipse_drawn_matches_the_eigen_decomposition(task2_runs):
    runs = [task2_runs["UC-EMDM"]]
    animator = Animator(runs)
    try:
        run = runs[0]
        arm = run.scenario.planar_arm
        for frame in (0, len(animator.indices) // 2, len(animator.indices) - 1):
            k = animator.indices[frame]
            drawn = animator.ellipse_at(frame)
            J = arm.jacobian(run.q[k])
            lam, U = np.linalg.eigh(J @ J.T)
            centred = drawn - run.p[k]
            # every vertex lies on x^T (J J^T)^-1 x = scale^2 ...
            quad = np.einsum("ij,jk,ik->i", centred, np.linalg.inv(J @ J.T), centred)
            np.testing.assert_allclose(quad, animator.scale**2, rtol=1e-9)
            # ... and the extent along each eigenvector is scale * sqrt(eigenvalue)
            for i in range(2):
                extent = np.abs(centred @ U[:, i]).max()
                assert extent == pytest.approx(animator.scale * np.sqrt(lam[i]), rel=1e-3)
    finally:
        animator.close()


def test_ellipse_points_for_a_known_jacobian():
    J = np.array([[2.0, 0.0], [0.0, 0.5]])
    pts = ellipse_points(J, np.array([1.0, -1.0]), 1.0)
    assert np.abs(pts[:, 0] - 1.0).max() == pytest.approx(2.0)
    assert np.abs(pts[:, 1] + 1.0).max() == pytest.approx(0.5)


def test_animate_command_writes_gif_and_mp4(tmp_path):
    out = tmp_path / "anim"
    assert (
        main(
            [
                "animate",
                "task2",
                "--set",
                "motion.max_time=1",
                "--pair",
                "C",
                "--speedup",
                "2",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    assert (out / "C-IVKC_vs_C-EMDM.gif").stat().st_size > 10_000
    imageio_ffmpeg = pytest.importorskip("imageio_ffmpeg")
    mp4 = out / "C-IVKC_vs_C-EMDM.mp4"
    frames, seconds = imageio_ffmpeg.count_frames_and_secs(str(mp4))
    assert frames >= 10 and seconds == pytest.approx(1.0 / 2 + 1.0, abs=0.15)


def test_animate_rejects_bad_speedup(tmp_path, capsys):
    assert main(["animate", "task2", "--speedup", "0", "--out", str(tmp_path / "a")]) == 2
    assert "--speedup must be > 0" in capsys.readouterr().err


# ------------------------------------------------------------------------------------- Pareto
@pytest.fixture(scope="module")
def task1_pareto():
    return pareto_study(emdm.load_scenario("task1"), "UC-EMDM")


def test_uc_emdm_front_lies_on_the_analytic_parabola(task1_pareto):
    data, run = task1_pareto
    sc = run.scenario
    assert [s["k"] for s in data["steps"]] == pareto_steps(run) == [0, 48, 96, 144]
    assert data["ratios"][0] == 0.0 and data["ratios"][-1] / data["ratios"][1] >= 1e6
    for step in data["steps"]:
        q = np.asarray(step["q"])
        kin = sc.planar_arm.kinematics(q)
        v = sc.motion.kp * (sc.motion.goal - kin.p)
        Jp = np.linalg.pinv(kin.J)
        N = np.eye(3) - Jp @ kin.J
        q0 = Jp @ v
        E0, M0 = 0.5 * q0 @ q0, kin.Jm @ q0
        curvature = 2 * np.linalg.norm(N @ kin.Jm) ** 2
        for point in step["points"]:
            expected_E = E0 + (point["M"] - M0) ** 2 / curvature
            assert point["E"] == pytest.approx(expected_E, rel=1e-9, abs=1e-12)
            # and each point is the exact optimum for its weights (closed form)
            r = point["w_manip"] / point["w_effort"]
            np.testing.assert_allclose(point["qd"], q0 + r * N @ kin.Jm, rtol=1e-10, atol=1e-12)
            assert point["kkt"] <= 1e-9


def test_on_the_parabola_nothing_right_of_the_vertex_is_dominated(task1_pareto):
    data, _ = task1_pareto
    for step in data["steps"]:
        # qd(r) = J^+ v + r N Jm with J^+ v orthogonal to N Jm: both E and M grow with r >= 0,
        # so no point of the sweep dominates another
        assert not any(p["dominated"] for p in step["points"])


def test_constrained_front_points_are_optimal(rng):
    sc = emdm.load_scenario("task2")
    ctrl = emdm.get_controller("C-EMDM")
    from conftest import reference_solve

    q = np.array([0.4, 1.1])
    for point in front_at(sc, ctrl, q, ratios(decades=6, per_decade=1)):
        weights = emdm.core.scenario.Weights(point["w_effort"], point["w_manip"], sc.weights.slack)
        qp = program_at(ctrl, sc, q, weights=weights).qp
        ref = reference_solve(qp.P, qp.c, qp.A, qp.b, qp.lb, qp.ub)
        np.testing.assert_allclose(point["qd"], ref[:2], atol=1e-8)


def test_dominance_marking():
    from emdm.studies.pareto import _mark_dominated

    pts = [{"E": 1.0, "M": 1.0}, {"E": 2.0, "M": 0.5}, {"E": 2.0, "M": 2.0}, {"E": 1.0, "M": 1.0}]
    _mark_dominated(pts)
    assert [p["dominated"] for p in pts] == [False, True, False, False]


def test_pareto_command(tmp_path, capsys):
    out = tmp_path / "par"
    with formats((".png",)):
        assert (
            main(["pareto", "task1", "--controller", "C-EMDM", "--grid", "4", "--out", str(out)])
            == 0
        )
    data = json.loads((out / "pareto.json").read_text())
    assert data["controller"] == "C-EMDM" and len(data["steps"]) == 4
    point = data["steps"][1]["points"][0]
    assert set(point) >= {"w_effort", "w_manip", "E", "M", "qd", "dominated"}
    grid = json.loads((out / "weight_grid.json").read_text())
    assert len(grid["runs"]) >= 4 and all("total_effort" in r for r in grid["runs"])
    for stem in ("pareto_front", "trade_off"):
        assert (out / f"{stem}.png").stat().st_size > 5000
    capsys.readouterr()
    assert main(["pareto", "task1", "--controller", "C-IVKC", "--out", str(tmp_path / "no")]) == 2
    assert "must weigh manipulability" in capsys.readouterr().err


def test_animate_a_spatial_arm_writes_an_mp4(tmp_path):
    """Three projections side by side make a frame of odd width; H.264 in yuv420p takes even
    sizes only, so the frames are cropped by a pixel (the Panda's MP4 used to fail)."""
    out = tmp_path / "anim"
    args = ["animate", "panda", "--set", "motion.max_time=0.5", "--controller", "C-EMDM"]
    assert main([*args, "--out", str(out)]) == 0
    imageio_ffmpeg = pytest.importorskip("imageio_ffmpeg")
    frames, _ = imageio_ffmpeg.count_frames_and_secs(str(out / "C-EMDM.mp4"))
    assert frames >= 10


def test_time_axes_end_at_the_last_arrival_only_when_the_others_stalled():
    """Fig. 5's time axes: Task 2's C-IVKC stalls at 4.35 s and the others arrive by 16.45 s, so
    the axes end at 16.45 s; Task 1 (all arrive) and a run that neither arrives nor has stalled
    keep the whole records."""
    from emdm.outputs.paper_figures import time_end

    task2 = emdm.load_scenario("task2")
    runs = [emdm.simulate(task2, c) for c in ("C-IVKC", "C-EMDM", "UC-IVKC", "UC-EMDM")]
    assert runs[0].stalled_from is not None and not runs[0].reached
    assert time_end(runs) == max(r.t[-1] for r in runs[1:]) == runs[1].t[-1]
    task1 = emdm.load_scenario("task1")
    assert time_end([emdm.simulate(task1, c) for c in ("C-IVKC", "C-EMDM")]) is None
    short = task2.with_overrides({"motion.max_time": 3.0})  # stopped before it stalled
    cut = emdm.simulate(short, "C-IVKC")
    assert not cut.reached and cut.stalled_from is None
    assert time_end([cut, runs[1]]) is None


def test_the_tracking_gap_is_the_slack_and_the_scaled_off_part(task2_runs):
    """Fig. 5(d): ||J qd - v_d|| from the states and commands equals what each program gave up,
    ||(1 - alpha) v_d + delta|| (J qd + delta = alpha v_d at every certified step), and is
    rounding only where the task is imposed."""
    from emdm.outputs.paper_figures import tracking_gap

    for name, run in task2_runs.items():
        gap = tracking_gap(run)
        given_up = np.linalg.norm((1.0 - run.alpha)[:, None] * run.v[:-1] + run.delta, axis=1)
        assert gap.shape == (run.steps,)
        assert np.allclose(gap, given_up, rtol=1e-9, atol=1e-12), name
    assert tracking_gap(task2_runs["UC-IVKC"]).max() < 1e-12
    assert tracking_gap(task2_runs["UC-EMDM"]).max() > 0.1  # its slack at work


def test_the_pair_figure_overlays_the_tip_paths_from_start_to_goal(tmp_path, drawn):
    """Fig. 1(d): each run's recorded tip path, from its start (the dot) to the goal (the star),
    beside the straight line; a figure has one fourth panel, the path or the gap."""
    from emdm.outputs import paper_figures as pf

    sc = emdm.load_scenario("task1", {"motion.max_time": 2.0})
    runs = [emdm.simulate(sc, name) for name in ("UC-IVKC", "UC-EMDM")]
    with formats((".png",)):
        pf.pair_figure(runs, tmp_path / "pair", path=True)
    panel = next(ax for ax in drawn[-1].axes if ax.get_title(loc="left") == "(d)")
    lines = panel.get_lines()
    for run in runs:
        assert any(np.array_equal(line.get_xydata(), run.p[:, :2]) for line in lines)
    goal = runs[0].p[0] + runs[0].e[0]
    assert any(np.allclose(line.get_xydata(), [goal]) for line in lines)
    assert any(np.allclose(line.get_xydata(), [runs[0].p[0]]) for line in lines)
    # (b): the effort over time, E at every step (the brief's), floored for the log axis
    panel = next(ax for ax in drawn[-1].axes if ax.get_title(loc="left") == "(b)")
    assert panel.get_yscale() == "log"
    for run in runs:
        effort = np.maximum(run.effort, pf.EFFORT_FLOOR)
        assert any(np.array_equal(line.get_ydata(), effort) for line in panel.get_lines())
    with pytest.raises(ValueError, match="one fourth panel"):
        pf.pair_figure(runs, tmp_path / "both", gap=True, path=True)


def test_the_arms_figure_draws_each_runs_postures_path_and_ellipse(tmp_path, drawn):
    """Task 1's stills in the paper: one view, every run's arm at its end (its joints'
    positions as the record gives them), its whole tip path, and its manipulability ellipse
    there, of the Jacobian's shape; the legend gives each run's final m."""
    from emdm.outputs import paper_figures as pf
    from emdm.outputs.animate import ellipse_points

    sc = emdm.load_scenario("task1", {"motion.max_time": 3.0})
    pairs = {
        "UC": [emdm.simulate(sc, n) for n in ("UC-IVKC", "UC-EMDM")],
        "C": [emdm.simulate(sc, n) for n in ("C-IVKC", "C-EMDM")],
    }
    with formats((".png",)):
        pf.arms_figure(pairs, tmp_path / "arms")
    (ax,) = drawn[-1].axes
    arm = sc.planar_arm
    lines = [line.get_xydata() for line in ax.get_lines()]
    patches = [p.get_xy() for p in ax.patches]
    runs = [r for pair in pairs.values() for r in pair]
    labels = [t.get_text() for t in drawn[-1].legends[0].get_texts()]
    ends = [r.stalled_from if r.stalled_from is not None else r.steps for r in runs]
    named = [f"{r.controller.name}  {r.m[k]:.3f}" for r, k in zip(runs, ends, strict=True)]
    assert labels == [*named, "start"]
    start = np.asarray(arm.joint_positions(runs[0].q[0]))[:, :2]
    assert any(x.shape == start.shape and np.allclose(x, start) for x in lines)
    for run, k in zip(runs, ends, strict=True):  # at its end: its stall, if it stalled
        posture = np.asarray(arm.joint_positions(run.q[k]))[:, :2]
        assert any(x.shape == posture.shape and np.allclose(x, posture) for x in lines)
        path = run.p[: k + 1, :2]
        assert any(x.shape == path.shape and np.allclose(x, path) for x in lines)
        # the ellipse's shape at the end: its axes are the Jacobian's singular values
        # (its 72 distinct points' mean: matplotlib may close the polygon once more)
        ell = next(x for x in patches if np.allclose(x[:72].mean(axis=0), run.p[k, :2], atol=1e-9))
        ref = ellipse_points(arm.jacobian(run.q[k]), run.p[k, :2], 1.0) - run.p[k, :2]
        drawn_shape = ell[: len(ref)] - run.p[k, :2]
        ratio = np.abs(drawn_shape).max() / np.abs(ref).max()
        assert np.allclose(drawn_shape, ratio * ref)


def test_the_task2_2_figure_draws_the_answers_four_quantities(tmp_path, drawn, task2_runs):
    """Slide 11's Task 2.2 chart: per run (the pair and the run without the dexterity term) its m,
    the effort spent so far (from 0, summing E dt), the tracking gap (the slack; an exact task
    sits on the floor) and its deepest joint's excursion past the limits."""
    from emdm.outputs import paper_figures as pf
    from emdm.sim.metrics import limit_excess

    runs = [task2_runs["UC-IVKC"], task2_runs["UC-EMDM"]]
    sc = emdm.load_scenario("task2", {"motion.max_time": 4.0, "weights.manipulability": 0.0})
    without = emdm.simulate(sc, "UC-EMDM")
    with formats((".png",)):
        pf.slack_figure(runs, tmp_path / "slack", without=("no term", without), medium=pf.SLIDE)
    ax_m, ax_e, ax_gap, ax_out = drawn[-1].axes[:4]
    for run in (*runs, without):
        assert any(np.array_equal(line.get_ydata(), run.m) for line in ax_m.get_lines())
        spent = np.concatenate(([0.0], np.cumsum(run.effort) * run.scenario.motion.dt))
        assert any(np.allclose(line.get_ydata(), spent) for line in ax_e.get_lines())
        gap = np.maximum(pf.tracking_gap(run), pf.GAP_FLOOR)
        assert any(np.allclose(line.get_ydata(), gap) for line in ax_gap.get_lines())
        out = limit_excess(run).max(axis=1)
        assert any(np.allclose(line.get_ydata(), out) for line in ax_out.get_lines())
    # UC-IVKC imposes the task: on the floor; UC-EMDM's slack lifts it off
    assert pf.tracking_gap(runs[0]).max() < 1e-9 < pf.tracking_gap(runs[1]).max()
    labels = [t.get_text() for t in drawn[-1].legends[0].get_texts()]
    assert labels == ["UC-IVKC", "UC-EMDM", "no term"]


def test_the_pair_figure_draws_a_run_without_a_cause_in_every_panel(tmp_path, drawn, task2_runs):
    """Fig. 8: Task 2.2's pair and, dotted and grey in every panel, its run without the
    dexterity term (``without``), named in the legend; its joints widen the strips' view."""
    from emdm.outputs import paper_figures as pf

    pair = [task2_runs["UC-IVKC"], task2_runs["UC-EMDM"]]
    sc = emdm.load_scenario("task2", {"motion.max_time": 4.0, "weights.manipulability": 0.0})
    extra = emdm.simulate(sc, "UC-EMDM")
    with formats((".png",)):
        pf.pair_figure(pair, tmp_path / "pair", gap=True, without=("no term", extra))
    fig = drawn[-1]
    dotted = [
        line
        for ax in fig.axes
        for line in ax.get_lines()
        if line.get_linestyle() == ":" and line.get_color() == "#666666"
    ]
    # m, E, ||e||, the gap and every joint's q and qd strip: one dotted line each
    assert len(dotted) == 4 + 2 * sc.n
    assert any(np.array_equal(line.get_ydata(), extra.m) for line in dotted)
    for j in range(sc.n):
        assert any(np.array_equal(line.get_ydata(), extra.q[:, j]) for line in dotted)
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert labels == ["UC-IVKC", "UC-EMDM", "no term"]


def test_the_stills_date_a_stall_as_the_record_does(tmp_path, drawn):
    """The pitch's stills draw a stalled run until its stall, dated by Run.stalled_from (the
    paper's date), and say it is still from then on."""
    from emdm.outputs import paper_figures as pf

    sc = emdm.load_scenario("task2", {"motion.max_time": 8.0})
    runs = [emdm.simulate(sc, name) for name in ("C-IVKC", "C-EMDM")]
    with formats((".png",)):
        pf.stills_figure(runs, tmp_path / "stills")
    stalled = runs[0].stalled_from
    assert stalled is not None and runs[1].stalled_from is None
    labels = [ax.get_xlabel() for ax in drawn[-1].axes]
    assert f"$t$ = 0 to {runs[0].t[stalled]:.2f} s, then still" in labels[0]  # as titles: 2 dp
    assert "then still" not in labels[1]


def test_speed_strips_far_beyond_the_limit_are_cut(tmp_path, drawn):
    """A joint whose speed goes far beyond its limit has its strip cut at FAR_BEYOND times the
    limit, on a plain linear axis (readings found a log band beyond it hard to read), with the
    peak the cut hides written inside the strip at the cut edge, "peak 8.73" (readings 138-140
    found bare numbers beside the strip cryptic; 209, 212, 214 could not see the violations); a
    strip within it spans every run and has nothing written."""
    from emdm.outputs import paper_figures as pf

    sc = emdm.load_scenario("task1", {"motion.max_time": 2.0})
    runs = [emdm.simulate(sc, name) for name in ("UC-IVKC", "UC-EMDM")]
    with formats((".png",)):
        pf.pair_figure(runs, tmp_path / "pair")
    strips = [ax for ax in drawn[-1].axes if ax.get_ylabel().startswith(r"$\dot q")]
    assert len(strips) == sc.n
    for j, ax in enumerate(strips):
        peak = max(np.abs(r.qd[:, j]).max() for r in runs)
        far = peak > pf.FAR_BEYOND * sc.arm.qd_max[j]
        assert ax.get_yscale() == "linear", j
        lo, hi = ax.get_ylim()
        limit = sc.arm.qd_max[j]
        written = [t.get_text() for t in ax.texts]
        if far:  # cut at FAR_BEYOND, the limits inside the view
            assert -pf.FAR_BEYOND * limit <= lo < -limit and limit < hi <= pf.FAR_BEYOND * limit
            assert max(hi, -lo) == pytest.approx(pf.FAR_BEYOND * limit)
            # each peak in the colour of the run it is (reading 216: the labels mixed them)
            highs = [(float(r.qd[:, j].max()), r) for r in runs]
            lows = [(float(r.qd[:, j].min()), r) for r in runs]
            ends = [max(highs, key=lambda e: e[0]), min(lows, key=lambda e: e[0])]
            expected = sorted(
                (
                    f"peak {float(f'{v:.3g}'):g}".replace("-", "\N{MINUS SIGN}"),
                    pf._style(r, pf.PAPER)["color"],
                )
                for v, r in ends
                if abs(v) > pf.FAR_BEYOND * limit
            )
            assert expected, j
            assert sorted((t.get_text(), t.get_color()) for t in ax.texts) == expected, j
        else:
            assert all(lo <= r.qd[:, j].min() and r.qd[:, j].max() <= hi for r in runs), j
            assert written == [], j
        assert not ax.artists  # nothing drawn beside the strip
    assert any(  # the case this guards: a strip cut
        max(np.abs(r.qd[:, j]).max() for r in runs) > max(np.abs(ax.get_ylim()))
        for j, ax in enumerate(strips)
    )


def test_convergence_markers_show_the_returned_answer_not_the_best_point(tmp_path, drawn):
    """A solver may return a point worse than the best it evaluated (cobyla trades objective
    against violation): the end marker is at the returned answer's error, the curve is the
    running best, and a solver without a returned answer ends its marker on its curve."""
    from emdm.outputs import paper_figures as pf

    curves: dict[str, pf.Curve] = {
        "returns-worse": ("gradient-free", [1, 2, 3], [1.0, 1e-3, 1e-12], 2e-8),
        "no-answer": ("gradient", [1, 2], [1.0, 1e-6], None),
    }
    with formats((".png",)):
        pf.convergence_figure([pf.ConvergencePanel("k = 7", "evaluations", curves)], tmp_path / "c")
    ax = drawn[-1].axes[0]
    markers = [ln for ln in ax.get_lines() if ln.get_linestyle() == "None"]
    ends = sorted((float(m.get_xdata()[0]), float(m.get_ydata()[0])) for m in markers)
    assert ends == [(2.0, 1e-6), (3.0, 2e-8)]
    best = next(ln for ln in ax.get_lines() if ln.get_label() == "returns-worse")
    assert list(best.get_ydata()) == [1.0, 1e-3, 1e-12]  # the curve itself unchanged


def test_convergence_panels_share_each_solvers_style_and_the_table_is_their_legend(tmp_path, drawn):
    """Fig. 6: one program per task side by side; a solver in both keeps its colour and
    marker, gradient-free ones are dashed, and with ``glyphs`` the figure draws no legend but
    saves each drawn solver's line and marker for the table's rows."""
    from emdm.outputs import paper_figures as pf

    task1 = {
        "active-set": ("exact", [1], [1e-17], 0.0),
        "slsqp": ("gradient", [1, 2], [1e-3, 1e-16], 1e-16),
    }
    task2 = {
        "slsqp": ("gradient", [2, 4, 6], [1.0, 1e-6, 1e-14], 1e-14),
        "cobyla": ("gradient-free", [1, 10, 50], [1.0, 1e-4, 1e-8], 3e-8),
    }
    panels = [
        pf.ConvergencePanel("Task 1, $k=0$", "iterations", task1),
        pf.ConvergencePanel("Task 2, $k=9$", "objective evaluations", task2),
    ]
    with formats((".png",)):
        pf.convergence_figure(panels, tmp_path / "conv", glyphs=tmp_path / "glyphs")
    fig = next(f for f in drawn if len(f.axes) == 2)
    assert not fig.legends and not any(ax.get_legend() for ax in fig.axes)
    styles = {}
    for ax, panel in zip(fig.axes, panels, strict=True):
        assert ax.get_xlabel() == panel.xlabel
        for line in ax.get_lines():
            if line.get_label() in panel.curves:
                style = (line.get_color(), line.get_marker())
                assert styles.setdefault(line.get_label(), style) == style
                dashed = panel.curves[line.get_label()][0] == "gradient-free"
                assert (line.get_linestyle() == "--") == dashed
    assert len(set(styles.values())) == 3  # three solvers, three styles
    # split by family: Task 2's gradient-free solvers get an axes of their own, on one scale
    panels[1] = pf.ConvergencePanel("Task 2, $k=9$", "objective evaluations", task2, True)
    with formats((".png",)):
        pf.convergence_figure(panels, tmp_path / "split", glyphs=tmp_path / "glyphs")
    fig = next(f for f in reversed(drawn) if len(f.axes) == 3)
    named = [{ln.get_label() for ln in ax.get_lines()} & {"slsqp", "cobyla"} for ax in fig.axes]
    assert named == [{"slsqp"}, {"slsqp"}, {"cobyla"}]
    assert len({ax.get_ylim() for ax in fig.axes}) == 1
    assert [ax.get_title() for ax in fig.axes[1:]] == ["gradient-based", "gradient-free"]
    assert fig.subfigs[1]._suptitle.get_text() == "Task 2, $k=9$"  # two programs: each named
    # a lone program split by family: its caption names it, the figure titles only the axes
    with formats((".png",)):
        pf.convergence_figure(panels[1:], tmp_path / "lone", glyphs=tmp_path / "glyphs")
    fig = next(f for f in reversed(drawn) if len(f.axes) == 2)
    assert [ax.get_title() for ax in fig.axes] == ["gradient-based", "gradient-free"]
    assert all(sub._suptitle is None for sub in fig.subfigs)
    assert pf.ConvergencePanel("t", "x", {"slsqp": task2["slsqp"]}, True).parts() == [
        ("", {"slsqp": task2["slsqp"]})
    ]  # one family only: not split
    # greyscale: each gradient-free solver its own broken line, every other one solid
    family = {"active-set": "exact", "slsqp": "gradient"} | {
        f"free{i}": "gradient-free" for i in range(7)
    }
    dashes = pf.solver_dashes(family)
    assert dashes["active-set"] == dashes["slsqp"] == "-"
    free = [dashes[f"free{i}"] for i in range(7)]
    assert len({str(d) for d in free}) == 7 and "-" not in free
    twelve = pf.solver_styles([f"s{i}" for i in range(12)])  # (the paper draws twelve)
    assert len({colour for colour, _ in twelve.values()}) == 12
    assert sorted(p.stem for p in (tmp_path / "glyphs").glob("*.png")) == [
        "active-set",
        "cobyla",
        "slsqp",
    ]
    glyph = next(f for f in drawn if f.axes and f.axes[0].get_lines() and len(f.axes) == 1)
    colours = {line.get_color() for line in glyph.axes[0].get_lines()}
    assert colours == {styles["active-set"][0]}  # the first glyph drawn: the first solver's


def test_a_convergence_panel_is_built_from_the_histories_record():
    """``convergence_panel``: the running best of |f - f*| + violation against the counted
    field, from 1 (an interior-point method's iteration 0 is its starting point, not drawn),
    solvers that do not count it left out, and each answer's error passed on."""
    from emdm.outputs.report.jobs import convergence_panel

    record = {
        "scenario": "task1",
        "controller": "C-EMDM",
        "representative_steps": {"first": 0, "least dexterous": 4},
        "optimum": {"first": 0.0, "least dexterous": -1.0},
        "solvers": {
            "interior-point": {
                "family": "exact",
                "histories": {
                    "least dexterous": [
                        {"iteration": 0, "objective": 5.0, "primal_residual": 1.0},
                        {"iteration": 1, "objective": -0.5, "primal_residual": 0.25},
                        {"iteration": 2, "objective": 0.0, "primal_residual": 0.5},
                        {"iteration": 3, "objective": -1.0, "primal_residual": 0.0},
                    ]
                },
                "returned": {"first": 0.0, "least dexterous": 0.0},
            },
            "daqp": {"family": "exact", "histories": {}, "returned": {"least dexterous": 0.0}},
            "cobyla": {
                "family": "gradient-free",
                "histories": {
                    "least dexterous": [
                        {"evaluations": 1, "objective": 0.0, "violation": 0.0},
                        {"evaluations": 2, "objective": -0.9, "violation": 0.0},
                    ]
                },
                "returned": {"least dexterous": 0.2},
            },
        },
    }
    panel = convergence_panel(record, "iteration")
    assert (
        panel is not None and panel.title == "Task 1 C-EMDM, $k=4$" and panel.xlabel == "iterations"
    )
    assert list(panel.curves) == ["interior-point"]
    family, counts, error, returned = panel.curves["interior-point"]
    assert (family, counts, returned) == ("exact", [1, 2, 3], 0.0)
    assert error[:2] == [0.75, 0.75] and error[2] == pytest.approx(1e-17)  # running best, floored
    panel = convergence_panel(record, "evaluations")
    assert panel is not None and list(panel.curves) == ["cobyla"]
    assert panel.curves["cobyla"][2] == [1.0, pytest.approx(0.1)]
    assert panel.curves["cobyla"][3] == 0.2
    record["solvers"] = {"daqp": record["solvers"]["daqp"]}
    assert convergence_panel(record, "iteration") is None


@pytest.mark.parametrize(
    ("low", "high", "power"), [(-6e-5, 1e-5, -5), (0.0, 30.0, 0), (0.0, 0.045, -2), (1e3, 5e4, 4)]
)
def test_the_power_folded_into_an_axis_label_is_the_one_its_ticks_left_out(low, high, power):
    """Fig. 2 writes a front's scale into its label (M (10^-5 m²/s)): the power is read from the
    offset text the formatter draws (a typographic minus included), 0 where it draws none."""
    from emdm.outputs import paper_figures as pf

    fig = pf.Figure()
    pf.FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.plot([low, high], [0.0, 1.0])
    ax.ticklabel_format(axis="x", style="sci", scilimits=(-2, 3), useMathText=True)
    fig.canvas.draw()
    assert pf._offset_power(ax.xaxis.get_major_formatter()) == power


def test_scaled_spans_are_hatched_apart_from_the_damper_tint(tmp_path, drawn):
    """Reading 111: in a greyscale print the task-scaled span and the damper zones were one
    grey. The span is hatched (in the axes and in the legend); the damper zones stay plain."""
    from matplotlib.patches import Rectangle

    from emdm.outputs import paper_figures as pf

    sc = emdm.load_scenario("task1", {"motion.max_time": 5.0})
    runs = [emdm.simulate(sc, name) for name in ("C-IVKC", "C-EMDM")]
    assert pf._common_scaled(runs)  # the case this guards
    with formats((".png",)):
        pf.pair_figure(runs, tmp_path / "pair", path=True)
    fig = drawn[-1]
    spans = [p for ax in fig.axes for p in ax.patches if isinstance(p, Rectangle) and p.get_hatch()]
    tints = [
        p for ax in fig.axes for p in ax.patches if isinstance(p, Rectangle) and not p.get_hatch()
    ]
    assert spans and tints  # the scaled spans hatched, the damper zones plain
    (legend,) = fig.legends
    assert any(getattr(h, "get_hatch", lambda: None)() == "////" for h in legend.legend_handles)


def test_the_pitch_trade_off_names_its_ends_and_the_nominal_point(tmp_path, drawn):
    """The pitch's Pareto slide, for peers: one panel, the whole runs on linear axes, no colour
    scale; the ends and the nominal weights named at their points, the runs that miss the goal
    named in a note and not drawn."""
    from emdm.outputs import paper_figures as pf

    grid = [
        {
            "w_effort": 0.1,
            "w_manip": 0.1 * r,
            "reached": r < 1e3,
            "total_effort": 5 + r / 100,
            "mean_manipulability": 0.25 + r / 2e4,
        }
        for r in (0.0, 50.0, 351.0, 1e3)
    ]
    with formats((".png",)):
        pf.pareto_slide_figure(50.0, grid, tmp_path / "p")
    fig = drawn[-1]
    (ax,) = fig.axes  # one idea, no colour bar
    assert (ax.get_xscale(), ax.get_yscale()) == ("linear", "linear")
    named = {t.get_text(): t.xy for t in ax.texts if hasattr(t, "xy")}
    assert named == {
        "effort only": (0.25, 5.0),
        "nominal": (0.25 + 50 / 2e4, 5.5),
        "$w_M/w_E=351$": (0.25 + 351 / 2e4, 5 + 3.51),
    }
    notes = [t.get_text() for t in ax.texts if not hasattr(t, "xy")]
    assert notes == ["$w_M/w_E=10^{3}$:\nmisses the goal"]
    drawn_x = {float(x) for c in ax.collections for x, _ in c.get_offsets()}
    assert 0.25 + 1e3 / 2e4 not in drawn_x  # the missed run is not drawn
    assert 0.25 + 351 / 2e4 in drawn_x


def test_the_workspace_figure_names_start_and_goal_on_a_slide_and_keeps_the_full_legend_in_print(
    tmp_path, drawn
):
    """Fig. 4 and its slide: the paper's legend names every mark (the arm, the goal, the
    reachable disc among them); the slide's names the start and the goal where they are (its
    legend the arms), leaves the grey disc unnamed and puts its legend under the axes (a
    ten-entry legend beside the axes took their width)."""
    from emdm.outputs import paper_figures as pf
    from emdm.outputs.report import explain

    sc = emdm.load_scenario("task2")
    pair = [emdm.simulate(sc, "C-IVKC"), emdm.simulate(sc, "C-EMDM")]
    geometry = explain.geometry(sc, pair[0].p[0])
    assert geometry is not None
    labels = {}
    for medium in (pf.PAPER, pf.SLIDE):
        with formats((".png",)):
            pf.workspace_figure(pair, geometry, tmp_path / medium.name, medium)
        fig = drawn[-1]
        (legend,) = fig.legends
        labels[medium.name] = [t.get_text() for t in legend.get_texts()]
        named = {t.get_text(): t.xy for t in fig.axes[0].texts if hasattr(t, "xy")}
        if medium is pf.SLIDE:
            assert named.keys() == {"start", "goal"}
            assert np.allclose(named["start"], pair[0].p[0][:2])
            assert np.allclose(named["goal"], sc.motion.goal)
        else:
            assert not named
    assert {"reachable", "arm: start, goal", "goal"} <= set(labels["paper"])
    # the slide names its arms too (reading 163), not the disc or the goal it labels in place
    assert set(labels["slide"]) == set(labels["paper"]) - {"reachable", "goal"}
    assert len(labels["slide"]) == 8


def test_the_task1_slide_shows_dexterity_effort_and_tracking_for_both_pairs(tmp_path, monkeypatch):
    """Slide 5's title has three claims (EMDM raises m, pays with effort, not with tracking):
    its figure draws each, per pair, from the runs: m(t), the effort spent so far and ||e||(t)
    (reading 133: tracking was said, not shown)."""
    from matplotlib.figure import Figure

    from emdm.outputs import paper_figures as pf

    drawn: list[Figure] = []
    save = Figure.savefig
    monkeypatch.setattr(
        Figure, "savefig", lambda self, *a, **k: drawn.append(self) or save(self, *a, **k)
    )
    sc = emdm.load_scenario("task1")
    pairs = {
        "unconstrained": [emdm.simulate(sc, "UC-IVKC"), emdm.simulate(sc, "UC-EMDM")],
        "constrained": [emdm.simulate(sc, "C-IVKC"), emdm.simulate(sc, "C-EMDM")],
    }
    with pf.png_only():
        pf.manipulability_figure(pairs, tmp_path / "task1-m")
    assert (tmp_path / "task1-m.png").exists() and len(drawn) == 1
    axes = [ax for ax in drawn[0].axes if ax.lines]
    assert len(axes) == 6  # three rows, a column per pair
    for col, runs in enumerate(pairs.values()):
        m_ax, e_ax, d_ax = axes[col], axes[2 + col], axes[4 + col]
        assert d_ax.get_yscale() == "log"
        for ax, series in (
            (m_ax, [r.m for r in runs]),
            (e_ax, [np.r_[0.0, np.cumsum(r.effort) * r.scenario.motion.dt] for r in runs]),
            (d_ax, [r.error_norm for r in runs]),
        ):
            lines = [ln for ln in ax.lines if len(ln.get_ydata()) > 2]
            assert len(lines) == 2
            for line, values in zip(lines, series, strict=True):
                assert np.allclose(line.get_ydata(), values)


def test_the_task2_2_slide_draws_the_run_without_the_dexterity_term(tmp_path, monkeypatch):
    """Slide 10 says what UC-EMDM does without its dexterity term; its figure draws that run
    (the evidence record's overrides) beside the pair, in every panel (reading 135), and the
    slack it says absorbs the desired velocity (the tracking gap, readings 150-151)."""
    from matplotlib.figure import Figure

    from emdm.outputs import paper_figures as pf
    from emdm.outputs.report.jobs import _without_term

    drawn: list[Figure] = []
    save = Figure.savefig
    monkeypatch.setattr(
        Figure, "savefig", lambda self, *a, **k: drawn.append(self) or save(self, *a, **k)
    )
    label, run = _without_term("UC-EMDM")
    assert run.scenario.weights.manipulability == 0.0 and "w_M=0" in label
    sc = emdm.load_scenario("task2")
    pair = [emdm.simulate(sc, "UC-IVKC"), emdm.simulate(sc, "UC-EMDM")]
    with pf.png_only():
        pf.slack_figure(pair, tmp_path / "effort", without=(label, run), medium=pf.SLIDE)
    for ax in drawn[0].axes:
        assert len(ax.lines) == 3 and np.allclose(ax.lines[2].get_xdata()[:2], run.t[:2])
    assert np.allclose(drawn[0].axes[0].lines[2].get_ydata(), run.m)
    # the fourth panel: how far past its joint limits each run goes (the slide's "by leaving
    # the joint limits ... by up to"), against the positions and limits directly
    arm = sc.arm
    for line, r in zip(drawn[0].axes[3].lines, [*pair, run], strict=True):
        deepest = [max(0.0, *(q - arm.q_max), *(arm.q_min - q)) for q in r.q]
        assert np.allclose(line.get_ydata(), deepest)
    assert max(drawn[0].axes[3].lines[0].get_ydata()) > 0.5  # UC-IVKC leaves them by 0.71 rad
    # a pair within its limits (Task 2 with them) has no such panel
    limited = [emdm.simulate(sc, "C-IVKC"), emdm.simulate(sc, "C-EMDM")]
    with pf.png_only():
        pf.slack_figure(limited, tmp_path / "effort2", medium=pf.SLIDE)
    assert len(drawn[-1].axes) == 3


def test_the_task2_slide_draws_each_runs_m_and_its_mean(tmp_path, drawn):
    """Slide 8's "at a mean m of 0.137 against 0.188" is drawn (reading 140): each run's m(t)
    and, as a line of its style, its mean over the run as the records give it, written at the
    right; the time axis ends at C-EMDM's arrival (C-IVKC stalled before it)."""
    from emdm.outputs import paper_figures as pf
    from emdm.sim.metrics import metrics

    sc = emdm.load_scenario("task2")
    pair = [emdm.simulate(sc, "C-IVKC"), emdm.simulate(sc, "C-EMDM")]
    with formats((".png",)):
        pf.mean_m_figure(pair, tmp_path / "m")
    ax = drawn[-1].axes[0]
    curves = [ln for ln in ax.lines if len(ln.get_xdata()) > 2]
    means = [ln for ln in ax.lines if len(ln.get_xdata()) == 2]
    for run, curve, mean in zip(pair, curves, means, strict=True):
        assert np.allclose(curve.get_ydata(), run.m)
        assert mean.get_ydata()[0] == pytest.approx(metrics(run)["mean_manipulability"])
    written = sorted(t.get_text() for t in ax.texts)
    assert written == sorted(f"{metrics(r)['mean_manipulability']:.3f}" for r in pair)
    assert ax.get_xlim()[1] == pytest.approx(pair[1].time_to_goal)


def test_the_solver_slide_says_each_verdict_and_what_it_cost(tmp_path, drawn):
    """Slide 11's verdicts in words beside each solver's time: exact (the paper's criterion),
    within 10^-k or off by g, out of bounds past 1e-6, and the median evaluations of those
    that count them (readings 140, 142: the slide said 522 evaluations without showing it)."""
    from emdm.outputs import paper_figures as pf

    def row(family, gap, violation, evaluations):
        return {
            "family": family,
            "median_time": 1e-3,
            "max_abs_gap": gap,
            "max_violation": violation,
            "median_evaluations": evaluations,
        }

    lab = {
        "solvers": {
            "qp": row("exact", 0.0, 0.0, 0.0),
            "sqp": row("gradient", 1e-14, 0.0, 6.0),
            "close": row("gradient-free", 3e-8, 1e-8, 58.0),
            "far": row("gradient-free", 0.11, 2e-6, 344.0),
        }
    }
    with formats((".png",)):
        pf.solver_verdict_figure(lab, 0.05, tmp_path / "v")
    words = sorted(t.get_text() for t in drawn[-1].axes[1].texts)
    assert words == sorted(
        [
            "exact",
            "exact, 6 evals",
            "within $10^{-7}$, 58 evals",
            "off by 0.11, out of bounds, 344 evals",
        ]
    )
    # the pitch leaves out the controls and fallbacks it names
    with formats((".png",)):
        pf.solver_verdict_figure(lab, 0.05, tmp_path / "v", omit=("close", "far"))
    assert [t.get_text() for t in drawn[-1].axes[0].get_yticklabels()] == ["qp", "sqp"]


def test_the_task2_1_figure_draws_c_ivkc_with_the_same_free_slack(tmp_path, monkeypatch):
    """Reading 169: Task 2.1's like-for-like comparison (C-IVKC given the free slack, Table
    II's row) was in the table only. Fig. 6 draws that run dotted: the evidence record's run,
    arriving where the record says."""
    from emdm.outputs import paper_figures as pf
    from emdm.outputs.report import jobs
    from emdm.outputs.report.config import EVIDENCE

    drawn: list = []
    monkeypatch.setattr(
        pf, "pair_figure", lambda runs, stem, medium=pf.PAPER, **kw: drawn.append(kw) or stem
    )
    jobs._job_pair_figures("task2", "C", tmp_path, jobs.QUICK)
    label, run = drawn[0]["without"]
    assert label == "C-IVKC, free slack"
    ev = next(e for e in EVIDENCE if e.key == "t2-c-slack-policy")
    overrides = {**ev.overrides, **ev.controller_overrides("C-IVKC")}
    again = emdm.simulate(emdm.load_scenario("task2", overrides), "C-IVKC")
    assert run.reached and np.array_equal(run.q, again.q)
    assert drawn[0]["gap"] is True
