"""The grid search that proves a planar obstacle scene solvable (emdm.studies.solvable)."""

from __future__ import annotations

import numpy as np
import pytest

from emdm.core.loading import load_scenario
from emdm.core.scenario import scenario_from_dict
from emdm.errors import ScenarioError
from emdm.studies.solvable import free_cells, goal_configurations, proved_solvable


def _with(obstacles):
    data = load_scenario("obstacle").to_dict()
    data["obstacles"] = obstacles
    return scenario_from_dict(data)


def test_goal_configurations_reach_the_goal_inside_the_box():
    sc = load_scenario("obstacle")
    qs = goal_configurations(sc)
    assert len(qs) > 100
    for q in qs[:: len(qs) // 50]:
        np.testing.assert_allclose(sc.planar_arm.forward(q), sc.motion.goal, atol=1e-12)
    lo = sc.arm.q_min + sc.damper.stop
    assert np.all(qs >= lo) and np.all(qs <= sc.arm.q_max - sc.damper.stop)


def test_an_empty_scene_is_proved_and_a_goal_inside_an_obstacle_is_not():
    data = load_scenario("obstacle").to_dict()
    data.pop("obstacles")
    assert proved_solvable(scenario_from_dict(data))["proved"]
    goal = load_scenario("obstacle").motion.goal
    walled = _with([{"shape": "circle", "center": list(goal), "radius": 0.05}])
    assert not proved_solvable(walled)["proved"]


def test_every_configuration_near_a_free_cell_keeps_the_stop_distance():
    """The margins are sound: configurations drawn within half a cell of free cells' centres,
    and on the segments between adjacent free centres, keep every link at least d_s away."""
    sc = _with(
        [
            {"shape": "circle", "center": [-0.3, 0.6], "radius": 0.08},
            {"shape": "circle", "center": [0.4, 0.5], "radius": 0.05},
        ]
    )
    cells = 32  # coarse: large margins, the bound matters most
    free, lo, h = free_cells(sc, cells)
    rng = np.random.default_rng(0)
    index = np.argwhere(free)
    stop = sc.obstacle_damper.stop
    worst = np.inf
    for i in index[rng.choice(len(index), 400, replace=False)]:
        centre = lo + (i + 0.5) * h
        for _ in range(5):
            q = centre + rng.uniform(-0.5, 0.5, sc.n) * h
            worst = min(worst, sc.obstacle_distances(q).min())
        j = i.copy()
        j[rng.integers(sc.n)] += 1
        if j.max() < cells and free[tuple(j)]:
            for s in np.linspace(0, 1, 7):
                q = centre + s * (lo + (j + 0.5) * h - centre)
                worst = min(worst, sc.obstacle_distances(q).min())
    assert worst >= stop - 1e-12
    assert not free.all()  # the obstacles took cells


def test_other_shapes_and_arms_are_refused():
    with pytest.raises(ScenarioError, match="circles only"):
        proved_solvable(load_scenario("panda-obstacles"))
