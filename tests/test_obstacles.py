"""Obstacles: closest points against an independent minimiser, distance Jacobians against finite
differences, the damper rows against a numpy twin built from the robot's drawn polyline, the
discrete-time guarantee (no link enters the stop distance of a static obstacle, at the most
adversarial command the rows allow and in closed loop), the scenario keys and their errors."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.optimize import linprog, minimize

from emdm import simulate
from emdm.core.controllers import get_controller, joint_bounds, program_at
from emdm.core.distance import closest_points
from emdm.core.loading import load_scenario
from emdm.core.obstacles import distance_jacobian
from emdm.core.scenario import scenario_from_dict
from emdm.errors import ScenarioError
from emdm.solvers import KKT_TOL


def with_obstacles(name, obstacles, q0=None, **damper):
    data = load_scenario(name).to_dict()
    data["obstacles"] = obstacles
    if q0 is not None:
        data["motion"]["q0"] = [float(v) for v in q0]
    if damper:
        data["obstacle_damper"] = damper
    return scenario_from_dict(data)


def test_closest_points_against_a_bounded_minimiser():
    rng = np.random.default_rng(1)
    for trial in range(300):
        P, Q, A, B = rng.normal(size=(4, 3))
        if trial % 5 == 0:
            Q = P.copy()  # a point against a segment
        if trial % 7 == 0:
            B = A.copy()
        if trial % 11 == 0:
            B = A + 0.7 * (Q - P)  # parallel segments
        x, y = np.empty(3), np.empty(3)
        d = closest_points(P, Q, A, B, x, y)

        def f(st, P=P, Q=Q, A=A, B=B):
            return np.sum((P + st[0] * (Q - P) - A - st[1] * (B - A)) ** 2)

        best = min(
            (
                minimize(f, s0, bounds=[(0, 1), (0, 1)], method="L-BFGS-B", tol=1e-14)
                for s0 in ([0.5, 0.5], [0, 0], [1, 1], [0, 1], [1, 0])
            ),
            key=lambda r: r.fun,
        )
        assert d == pytest.approx(np.sqrt(best.fun), abs=1e-7)
        assert np.linalg.norm(x - y) == pytest.approx(d, abs=1e-15)
        # x lies on [P, Q] and y on [A, B]
        for point, a, b in ((x, P, Q), (y, A, B)):
            seg = b - a
            s = 0.0 if not seg @ seg else float((point - a) @ seg / (seg @ seg))
            assert -1e-12 <= s <= 1 + 1e-12
            np.testing.assert_allclose(point, a + s * seg, atol=1e-12)


@pytest.mark.parametrize("name", ["task1", "panda", "ur5"])
def test_distance_jacobian_against_finite_differences(name):
    rng = np.random.default_rng(2)
    sc0 = load_scenario(name)
    dim = 2 if name == "task1" else 3
    shape = "circle" if dim == 2 else "sphere"
    far = [5.0] * dim
    sc = with_obstacles(
        name,
        [
            {"shape": shape, "center": far, "radius": 0.1, "velocity": [0.1] * dim},
            {"shape": "segment" if dim == 2 else "capsule", "points": [far, [6.0] * dim]},
        ],
    )
    checked = 0
    for _ in range(20):
        q = rng.uniform(sc0.arm.q_min, sc0.arm.q_max)
        for link in range(sc.n + 1):
            for o in range(2):
                d, Jd, _, _ = distance_jacobian(sc, q, link, o)
                assert d == pytest.approx(sc.obstacle_distances(q)[link, o], abs=1e-14)
                h = 1e-6
                fd = np.array(
                    [
                        (
                            sc.obstacle_distances(q + h * np.eye(sc.n)[j])[link, o]
                            - sc.obstacle_distances(q - h * np.eye(sc.n)[j])[link, o]
                        )
                        / (2 * h)
                        for j in range(sc.n)
                    ]
                )
                np.testing.assert_allclose(Jd, fd, atol=2e-8)
                checked += 1
        # a moving obstacle: d d / d t = -n . v
        _, _, x, w = distance_jacobian(sc, q, sc.n - 1, 0, t=1.0)
        normal = (x - w) / np.linalg.norm(x - w)
        rate = (
            sc.obstacle_distances(q, 1.0 + 1e-6)[sc.n - 1, 0]
            - sc.obstacle_distances(q, 1.0 - 1e-6)[sc.n - 1, 0]
        ) / 2e-6
        assert rate == pytest.approx(-normal @ np.r_[[0.1] * dim, [0.0] * (3 - dim)], abs=1e-8)
    assert checked == 20 * (sc.n + 1) * 2


def polyline(sc, q):
    """The drawn polyline (numpy model), as 3-D points with the tip repeated for a planar arm."""
    pts = sc.robot.joint_positions(q)
    if pts.shape[1] == 2:
        pts = np.vstack((np.hstack((pts, np.zeros((len(pts), 1)))), [[*pts[-1], 0.0]]))
    return pts


def numpy_rows(sc, q, lb, ub):
    """The obstacle rows, untightened (NEO's damper at the link endpoints), from the numpy
    polyline and finite-difference Jacobians of its points: ``(G, h, per-row endpoint)``."""
    od = sc.obstacle_damper
    pts = polyline(sc, q)
    G, h, where = [], [], []
    for ob in sc.obstacles:
        a = np.r_[ob.a, [0.0] * (3 - ob.a.size)]
        b = np.r_[ob.b, [0.0] * (3 - ob.b.size)]
        for i in range(len(pts) - 1):
            x, w = np.empty(3), np.empty(3)
            span = closest_points(pts[i], pts[i + 1], a, b, x, w)
            d = span - ob.radius - od.link_radius
            if d >= od.influence:
                continue
            n = (x - w) / span
            for e in (i, i + 1):
                if e == 0 or (e == i + 1 and np.all(pts[e] == pts[i])):
                    continue
                Je = np.array(
                    [
                        (polyline(sc, q + 1e-6 * u)[e] - polyline(sc, q - 1e-6 * u)[e]) / 2e-6
                        for u in np.eye(sc.n)
                    ]
                ).T
                d_e = n @ (pts[e] - w) - ob.radius - od.link_radius
                G.append(-n @ Je)
                h.append(od.gain * (d_e - od.stop) / (od.influence - od.stop))
                where.append(e)
    return np.array(G), np.array(h), where


def near_a_link(name, rng, gap):
    """``(q, scenario)``: a random configuration of preset ``name`` and a 0.1 m circle or sphere
    whose surface is ``gap`` (a range, m) from a random point of a random link; ``None`` when
    another link starts within the stop distance."""
    sc0 = load_scenario(name)
    dim = sc0.robot.dim
    q = rng.uniform(sc0.arm.q_min + 0.3, sc0.arm.q_max - 0.3)
    pts = polyline(sc0, q)
    link = int(rng.integers(1, sc0.n))
    point = pts[link] + rng.uniform(0.2, 0.8) * (pts[link + 1] - pts[link])
    direction = rng.normal(size=3)
    if dim == 2:
        direction[2] = 0.0
    centre = point + direction / np.linalg.norm(direction) * (0.1 + rng.uniform(*gap))
    obstacle = {"shape": "circle" if dim == 2 else "sphere", "center": list(centre[:dim])}
    try:
        return q, with_obstacles(name, [{**obstacle, "radius": 0.1}], q0=q)
    except ScenarioError:
        return None


@pytest.mark.parametrize("name", ["task1", "panda"])
def test_rows_match_a_numpy_twin_and_keep_every_link_out_at_the_worst_command(name):
    """The compiled rows equal the numpy twin's up to the tightening (which is >= 0) or are
    implied by the joint bounds, and at the most adversarial vertices of the command polytope no
    link ends inside the stop distance."""
    rng = np.random.default_rng(3)
    ctrl = get_controller("C-EMDM")
    found = left_out = 0
    for _ in range(60):
        drawn = near_a_link(name, rng, (0.035, 0.12))
        if drawn is None:
            continue  # another link starts within the stop distance
        q, sc = drawn
        if sc.obstacle_distances(q).min() <= sc.obstacle_damper.stop:
            continue
        qp = program_at(ctrl, sc, q).qp
        if not qp.n_rows:
            continue
        found += 1
        G, h = qp.G[:, : sc.n], qp.h
        tG, th, _ = numpy_rows(sc, q, qp.lb, qp.ub)
        # every twin row is a compiled row (same normal and Jacobian) with h no higher, or one
        # the joint bounds imply (left out of the program)
        for g, hh in zip(tG, th, strict=True):
            match = np.flatnonzero(np.abs(G - g).max(axis=1) < 1e-7)
            if not match.size:
                top = np.maximum(g * qp.lb[: sc.n], g * qp.ub[: sc.n]).sum()
                assert top < hh, "a twin row is missing and the bounds do not imply it"
                left_out += 1
                continue
            assert h[match].min() <= hh + 1e-12
        # the most adversarial commands: vertices of {G qd <= h, lb <= qd <= ub}
        for _ in range(8):
            c = rng.normal(size=sc.n)
            res = linprog(
                c,
                A_ub=G,
                b_ub=h,
                bounds=list(zip(qp.lb[: sc.n], qp.ub[: sc.n], strict=True)),
                method="highs",
            )
            assert res.status == 0
            after = sc.obstacle_distances(q + sc.motion.dt * res.x)
            assert after.min() >= sc.obstacle_damper.stop - 1e-12
    assert found >= 20
    assert left_out > 0  # the path that leaves implied rows out was exercised


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    st.lists(
        st.tuples(st.floats(-1.1, 1.1), st.floats(-1.1, 1.1), st.floats(0.03, 0.2)),
        min_size=1,
        max_size=4,
    ),
    st.sampled_from(["C-EMDM", "C-IVKC", "NEO"]),
)
def test_no_link_enters_the_stop_distance_in_closed_loop(circles, name):
    obstacles = [{"shape": "circle", "center": [x, y], "radius": r} for x, y, r in circles]
    try:
        sc = with_obstacles("task1", obstacles)
    except ScenarioError:
        return  # an obstacle over the start: refused, as tested below
    try:
        run = simulate(sc, name)
    except Exception as exc:  # a run may stop (no admissible command); its record still holds
        run = exc.run  # type: ignore[attr-defined]
    assert run.clearance.min() >= sc.obstacle_damper.stop - 1e-12
    assert np.all(run.kkt <= KKT_TOL)


def test_blind_controllers_do_not_see_obstacles():
    sc = with_obstacles("task1", [{"shape": "circle", "center": [-0.35, 0.55], "radius": 0.08}])
    blind = simulate(sc, get_controller("C-EMDM").blind())
    seeing = simulate(sc, "C-EMDM")
    assert blind.clearance.min() < 0 < sc.obstacle_damper.stop <= seeing.clearance.min()
    assert blind.rows.max() == 0 < seeing.rows.max()
    mmc, neo = simulate(sc, "MMC"), simulate(sc, "NEO")
    assert mmc.clearance.min() < 0 and neo.clearance.min() >= sc.obstacle_damper.stop


def test_obstacles_round_trip_through_toml():
    sc = with_obstacles(
        "task1",
        [
            {"shape": "circle", "center": [-0.35, 0.75], "radius": 0.08, "velocity": [0.01, 0]},
            {"shape": "segment", "points": [[-1.0, -0.5], [-0.5, -0.5]], "radius": 0.02},
        ],
        influence=0.2,
        stop=0.02,
        gain=0.5,
        link_radius=0.01,
    )
    import tomllib

    back = scenario_from_dict(tomllib.loads(sc.to_toml()))
    assert back.to_toml() == sc.to_toml()
    assert back.obstacle_data == sc.obstacle_data
    assert "[[obstacles]]" in sc.to_toml() and "[obstacle_damper]" in sc.to_toml()
    assert "obstacle" not in load_scenario("task1").to_toml()


@pytest.mark.parametrize(
    ("obstacles", "damper", "key", "words"),
    [
        (
            [{"shape": "sphere", "center": [0, 0], "radius": 0.1}],
            {},
            "obstacles[0].shape",
            "spatial arms",
        ),
        (
            [{"shape": "circle", "center": [0, 0, 1], "radius": 0.1}],
            {},
            "obstacles[0].center",
            "2 values",
        ),
        ([{"shape": "circle", "center": [-1, 1]}], {}, "obstacles[0].radius", "required"),
        (
            [{"shape": "circle", "center": [-1, 1], "radius": -1}],
            {},
            "obstacles[0].radius",
            "between",
        ),
        (
            [{"shape": "circle", "center": [-1, 1], "radius": 0.1, "colour": 1}],
            {},
            "obstacles[0].colour",
            "unknown key",
        ),
        ([{"shape": "segment", "center": [-1, 1]}], {}, "obstacles[0].center", "has points"),
        (
            [{"shape": "circle", "center": [0.2, 0.0], "radius": 0.05}],
            {},
            "obstacles[0]",
            "link 1 starts",
        ),
        (
            [{"shape": "circle", "center": [-1, 1], "radius": 0.1}],
            {"stop": 0.2},
            "obstacle_damper.stop",
            "below",
        ),
        (
            [{"shape": "circle", "center": [-1, 1], "radius": 0.1}],
            {"gain": 5.0},
            "obstacle_damper.gain",
            "pass the stop distance",
        ),
        ("circle", {}, "obstacles", "list of tables"),
    ],
)
def test_bad_obstacles_get_one_line_errors(obstacles, damper, key, words):
    with pytest.raises(ScenarioError) as info:
        with_obstacles("task1", obstacles, **damper)
    message = str(info.value)
    assert key in message and words in message and "\n" not in message


def test_without_the_tightening_a_panda_link_can_cross_the_stop_distance():
    """The test above can fail: NEO's rows as they are (the twin's, untightened, under the same
    joint bounds) admit commands that end a Panda link inside the stop distance."""
    rng = np.random.default_rng(3)
    sc0 = load_scenario("panda")
    worst = np.inf
    for _ in range(120):
        drawn = near_a_link("panda", rng, (0.031, 0.06))
        if drawn is None:
            continue
        q, sc = drawn
        bounds = joint_bounds(sc, q)
        G, h, _ = numpy_rows(sc, q, bounds.lo, bounds.hi)
        if not len(h):
            continue
        for _ in range(8):
            res = linprog(
                rng.normal(size=sc.n),
                A_ub=G,
                b_ub=h,
                bounds=list(zip(bounds.lo, bounds.hi, strict=True)),
                method="highs",
            )
            if res.status == 0:
                worst = min(worst, sc.obstacle_distances(q + sc.motion.dt * res.x).min())
    assert worst < sc0.obstacle_damper.stop


@pytest.mark.parametrize("preset", ["obstacle", "panda-obstacles"])
def test_presets_c_emdm_goes_around_where_the_blind_collide_and_c_ivkc_stalls(preset):
    """The evidence runs of docs/mathematics.md, "Obstacles": the straight path is blocked."""
    sc = load_scenario(preset)
    stop = sc.obstacle_damper.stop
    around, neo = simulate(sc, "C-EMDM"), simulate(sc, "NEO")
    stalled = simulate(sc, "C-IVKC")
    blind = simulate(sc, get_controller("C-EMDM").blind())
    assert around.reached and around.clearance.min() >= stop
    assert neo.reached and neo.clearance.min() >= stop
    assert not stalled.reached and stalled.clearance.min() >= stop
    assert stalled.stalled_from is not None
    assert blind.reached and blind.clearance.min() < stop
    assert np.all(around.kkt <= KKT_TOL) and np.all(stalled.kkt <= KKT_TOL)


def test_clearance_objective_is_the_gradient_of_the_nearness_potential():
    """The ``clearance`` term adds ``w_O grad(V)`` to ``c``, V = 1/2 sum ((d_i - d)/(d_i - d_s))^2
    over the pairs within influence: against finite differences of V from the distances."""
    sc = load_scenario("obstacle")
    od = sc.obstacle_damper
    rng = np.random.default_rng(5)

    def potential(q):
        D = sc.obstacle_distances(q)
        near = np.minimum(D, od.influence)
        return 0.5 * np.sum(((od.influence - near) / (od.influence - od.stop)) ** 2)

    ctrl = get_controller("C-EMDM")
    w = 2.0
    with_term = sc.with_overrides({"weights.clearance": w})
    checked = 0
    states = simulate(sc, "C-IVKC").q  # it stalls against the obstacle: states near it
    for k in rng.choice(len(states), 60, replace=False):
        q = states[k]
        if sc.obstacle_distances(q).min() <= od.stop or potential(q) == 0.0:
            continue
        c_on = program_at(ctrl, with_term, q).qp.c[: sc.n]
        c_off = program_at(ctrl, sc, q).qp.c[: sc.n]
        grad = np.array(
            [(potential(q + 1e-6 * u) - potential(q - 1e-6 * u)) / 2e-6 for u in np.eye(sc.n)]
        )
        np.testing.assert_allclose(c_on - c_off, w * grad, atol=1e-6)
        checked += 1
    assert checked >= 10


def test_random_scenes_are_seeded_and_valid():
    from emdm.studies.obstacle_bench import random_scenes, scene
    from emdm.studies.stats import wilson

    lo, hi = wilson(74, 100)
    assert 0.64 < lo < 0.66 and 0.81 < hi < 0.83  # Wilson's interval of 74/100
    rng = np.random.default_rng(4)
    sc = scene("obstacle", 4, rng, (0.03, 0.05))
    assert len(sc.obstacles) == 4 and sc.obstacle_distances(sc.motion.q0).min() > 0.03
    first = random_scenes("obstacle", 2, 2, (0.03, 0.05), seed=7)
    again = random_scenes("obstacle", 2, 2, (0.03, 0.05), seed=7)
    assert repr(first) == repr(again)  # equal, NaN medians included
    assert set(first["controllers"]) == {
        "C-EMDM",
        "C-EMDM task held",
        "C-EMDM blind",
        "NEO",
        "NEO blind",
    }
    assert first["controllers"]["C-EMDM"]["collisions"] == 0.0
    assert first["emdm_equals_neo"]  # one program in a scene with obstacles (docs)


def test_run_folder_keeps_clearance_and_rows_and_the_command_line_says_how_each_run_fared(
    tmp_path, capsys
):
    from emdm.cli import main
    from emdm.outputs.records import read_run

    out = tmp_path / "out"
    assert (
        main(
            [
                "run",
                "obstacle",
                "--controller",
                "C-EMDM",
                "--controller",
                "C-IVKC",
                "--controller",
                "UC-EMDM",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    printed = capsys.readouterr().out
    assert "C-IVKC: stalled in front of an obstacle" in printed
    assert "UC-EMDM: link" in printed and "does not see the obstacles" in printed
    assert "clearance[m]" in printed
    header = (out / "trajectories" / "C-EMDM.csv").read_text().splitlines()[0]
    assert header.endswith(",clearance")
    for name in ("C-EMDM", "C-IVKC"):
        back, run = read_run(out, name), simulate(load_scenario("obstacle"), name)
        np.testing.assert_array_equal(back.clearance, run.clearance)
        np.testing.assert_array_equal(back.rows_active, run.rows_active)
        np.testing.assert_array_equal(back.qd, run.qd)


def test_a_link_caught_between_rows_is_stood_still_not_stopped():
    """With a circle beside link 2 at the start, C-IVKC (no slack) meets steps whose rows, at the
    speed floor, all ask to move away while the task allows no motion: the step is built again
    without the floor (standing still is admissible and exact) instead of ending the run."""
    sc = with_obstacles("task1", [{"shape": "circle", "center": [0.5, 0.0], "radius": 0.1}])
    run = simulate(sc, "C-IVKC")
    assert not run.reached and run.steps == sc.max_steps
    assert run.clearance.min() >= sc.obstacle_damper.stop
    assert run.fallback.any() and np.all(run.kkt <= KKT_TOL)


def test_a_stall_whose_largest_scale_cannot_be_certified_stands_still():
    """A random scene (seed 0 of the benchmark) where C-IVKC stalls at the stop distance with a
    largest task scale of about 3e-11: its feasible set is narrower than the certificate's bound
    tolerance, so every solver's answer was refused and the run stopped at step 222. The scale 0
    is admissible there (standing still keeps every bound and row) and certified."""
    circles = [
        ([-0.4917033136329308, 0.2842445653397682], 0.07020646336685524),
        ([0.7146022368084359, 0.935592144741955], 0.040640553176577596),
        ([0.12852753254429894, 0.18198289229653125], 0.05188169529708199),
    ]
    sc = with_obstacles(
        "task1", [{"shape": "circle", "center": c, "radius": r} for c, r in circles]
    )
    run = simulate(sc, "C-IVKC")  # raised NoSolution at step 222 before
    assert run.steps == sc.max_steps and not run.reached
    assert run.alpha[222] == 0.0 and run.policy[222] == "scale"  # stood still there
    assert run.clearance.min() >= sc.obstacle_damper.stop - 1e-12
    assert np.all(run.kkt <= KKT_TOL) and np.all(run.bound_excess <= 1e-12)
