"""The fuzzing harness: hostile obstacles and command lines against the contract of every input.

A scenario is built or refused in one printable line; a command exits 0, or 2 with one line on
stderr and no traceback; nothing is written outside ``--out``; results already in ``--out`` stay
byte for byte when the command fails. A short profile runs in ``make test``; ``make fuzz`` runs
the long one (``EMDM_FUZZ_EXAMPLES``, 10,000 cases per test by default there).
"""

from __future__ import annotations

import contextlib
import io
import os
import tempfile
import warnings
from pathlib import Path
from typing import Any

import numpy as np
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from emdm import NoSolution, ScenarioError, load_scenario, scenario_from_dict, simulate
from emdm.cli import main
from emdm.core.schema import SCHEMA

LONG = int(os.environ.get("EMDM_FUZZ_EXAMPLES", "0"))


def examples(short: int) -> Any:
    """Hypothesis settings: ``short`` cases in ``make test``, ``EMDM_FUZZ_EXAMPLES`` on demand."""
    return settings(
        max_examples=LONG or short,
        deadline=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
    )


numbers = st.floats(-5, 5, allow_nan=False) | st.sampled_from([0.0, -0.0, 1e-300, 1e300])
hostile = st.none() | st.booleans() | st.floats() | st.text(max_size=6) | st.integers(-3, 10**9)
vectors = st.lists(numbers, min_size=0, max_size=4)
value = hostile | vectors | st.lists(vectors, max_size=3)

obstacle = st.dictionaries(
    st.sampled_from(["shape", "center", "radius", "points", "velocity", "x"]),
    st.one_of(
        st.sampled_from(["circle", "sphere", "segment", "capsule", "box", ""]),
        value,
    ),
    max_size=5,
)


def wellformed(dim: int) -> st.SearchStrategy[dict[str, Any]]:
    """Obstacles that may well be valid: circles or spheres, segments or capsules, some moving."""
    point = st.lists(st.floats(-1.2, 1.2), min_size=dim, max_size=dim)
    velocity = st.lists(st.floats(-0.5, 0.5), min_size=dim, max_size=dim)
    round_ = st.fixed_dictionaries(
        {
            "shape": st.just("circle" if dim == 2 else "sphere"),
            "center": point,
            "radius": st.floats(0.0, 0.4),
        },
        optional={"velocity": velocity},
    )
    long_ = st.fixed_dictionaries(
        {
            "shape": st.just("segment" if dim == 2 else "capsule"),
            "points": st.lists(point, min_size=2, max_size=2),
        },
        optional={"radius": st.floats(0.0, 0.2), "velocity": velocity},
    )
    return round_ | long_


@examples(150)
@given(
    st.data(),
    st.sampled_from(["task1", "panda"]),
    st.just({})
    | st.dictionaries(st.sampled_from([*SCHEMA["obstacle_damper"], "x"]), value, max_size=2),
)
def test_fuzzed_obstacles_give_a_scenario_or_one_line_error(data, preset, damper):
    dim = 2 if preset == "task1" else 3
    obstacles = data.draw(
        st.lists(wellformed(dim), max_size=4)
        | st.lists(wellformed(dim) | obstacle, max_size=4)
        | hostile,
        label="obstacles",
    )
    layout = load_scenario(preset).to_dict()
    layout["obstacles"] = obstacles
    layout["obstacle_damper"] = {**layout.get("obstacle_damper", {}), **damper}
    layout["motion"] = {**layout["motion"], "max_time": 0.2}
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            sc = scenario_from_dict(layout, source="fuzz")
    except ScenarioError as exc:
        event("refused: " + str(exc).split(": ")[1][:22])
        text = str(exc)
        assert text.startswith("fuzz") and "\n" not in text and text.isprintable()
        return
    event(f"built with {len(sc.obstacles)} obstacles")
    try:
        run = simulate(sc, "C-EMDM")
    except NoSolution as exc:  # a run may stop, naming the step; its record still holds
        run = exc.run  # type: ignore[attr-defined]
    assert np.all(np.isfinite(run.q)) and np.all(np.isfinite(run.qd))
    stop = sc.obstacle_damper.stop
    static = all(not np.any(o.velocity) for o in sc.obstacles)
    if static and sc.obstacles:
        assert run.clearance.min() >= min(stop, run.clearance[0]) - 1e-12


# ------------------------------------------------------------------------------ command lines
keys = [f"{s}.{k}" for s, ks in SCHEMA.items() for k in ks]
settings_values = st.one_of(
    st.sampled_from(["0", "-1", "nan", "inf", "1e300", "abc", "[1, 2]", "[]", '"x"', "true"]),
    st.floats(-10, 10, allow_nan=False).map(repr),
)
option = st.one_of(
    st.tuples(st.just("--set"), st.builds("{}={}".format, st.sampled_from(keys), settings_values)),
    st.tuples(
        st.just("--controller"),
        st.sampled_from(["C-EMDM", "uc-ivkc", "NEO", "MMC", "X", "", "C-EMDM,C-IVKC"]),
    ),
    st.tuples(st.just("--solver"), st.sampled_from(["active-set", "daqp", "nope", ""])),
    st.tuples(st.just("--fallback"), st.sampled_from(["none", "quadprog", "x"])),
    st.tuples(
        st.sampled_from(["--bogus", "--set", "--out"]),
    ),
)


def _tree(root: Path) -> dict[str, bytes]:
    return {
        str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()
    }


@examples(40)
@given(
    st.sampled_from(["run", "scenario"]),
    st.sampled_from(["task1", "task2", "obstacle", "panda", "nope", ""]),
    st.lists(option, max_size=4),
    st.sampled_from(["new", "earlier", "foreign"]),
)
def test_fuzzed_command_lines_exit_0_or_one_line_and_lose_nothing(command, scenario, opts, out):
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        target = root / "out"
        if out != "new":
            assert main(["run", "task1", "--controller", "C-EMDM", "--out", str(target)]) == 0
        if out == "foreign":
            (target / "mine.txt").write_text("the user's", encoding="utf-8")
        before = _tree(root)
        argv = [command, scenario, *[a for o in opts for a in o], "--set", "motion.max_time=0.3"]
        if command == "run":
            argv += ["--out", str(target)]
        err, std = io.StringIO(), io.StringIO()
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(std):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                try:
                    code = main(argv)
                except SystemExit as exc:  # argparse's own exit
                    code = exc.code if isinstance(exc.code, int) else 2
        text = err.getvalue()
        event(f"exit {code}")
        assert code in (0, 2), (argv, code, text)
        assert "Traceback" not in text and "Traceback" not in std.getvalue()
        after = _tree(root)
        outside = {k for k in after if not k.startswith("out")} ^ {
            k for k in before if not k.startswith("out")
        }
        assert not outside, outside  # nothing written, or lost, outside --out
        if code == 2:
            lines = [line for line in text.splitlines() if line.strip()]
            assert len(lines) == 1, (argv, text)
            if "written to" in lines[0] and lines[0].startswith("emdm: error: run stopped"):
                # the documented partial run (README): what finished, and the partial run, are
                # written as complete results, and the one line says so
                assert (target / ".emdm-results").is_file() and (target / "metrics.json").is_file()
            else:
                assert after == before  # earlier results, and the user's files, byte for byte
        if out == "foreign" and command == "run":
            assert (target / "mine.txt").read_text(encoding="utf-8") == "the user's"


def test_an_empty_string_for_any_key_that_is_not_text_is_one_line():
    """Found by the long fuzz run: ``""`` passed every number key as "left out" and ended in a
    TypeError; only arm.lengths and arm.dh may be left out that way."""
    for section, keys in SCHEMA.items():
        for key, spec in keys.items():
            if spec.kind == "str" or spec.default == "":
                continue
            layout = load_scenario("obstacle").to_dict()
            layout.setdefault(section, {})[key] = ""
            try:
                scenario_from_dict(layout, source="fuzz")
            except ScenarioError as exc:
                assert str(exc).startswith(f"fuzz: {section}.{key}: "), str(exc)
                assert "\n" not in str(exc)
            else:
                raise AssertionError(f"{section}.{key} = '' accepted")
