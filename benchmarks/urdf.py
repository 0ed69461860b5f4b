"""URDF arms: accuracy against two references, loading time, and per-step cost against DH.

`python benchmarks/urdf.py` writes benchmarks/urdf.{json,md}:

- accuracy: for each robot description the test suite loads (tests/test_urdf.py), the largest
  difference over 20 random configurations of the pose, the geometric Jacobian, the Hessian, the
  manipulability and its gradient from the numpy statement of URDF's semantics
  (tests/urdf_reference.py; complex steps for the Hessian, 40 digits for m and dm/dq), and of the
  pose and Jacobian from Pinocchio (its version printed);
- loading: the median time of reading a file into its chain (`read_urdf`) and of loading a
  scenario that names it, in a warm process, and in a new process the first read after importing
  emdm (the import of yourdfpy and trimesh included);
- per step: the Panda from its URDF (to panda_link8) against the DH `panda` preset with the same
  limits, C-EMDM through `emdm.simulate`, medians over repeats, run alternately in one process.
"""

from __future__ import annotations

import json
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

import pinocchio as pin  # noqa: E402
import test_urdf as suite  # noqa: E402
import urdf_reference as ref  # noqa: E402

import emdm  # noqa: E402
from emdm import SerialArm  # noqa: E402
from emdm.core.loading import load_scenario  # noqa: E402
from emdm.core.scenario import scenario_from_dict  # noqa: E402
from emdm.core.urdf import read_urdf  # noqa: E402
from emdm.studies.bench import _median_time  # noqa: E402

QUANTITIES = (
    "pose",
    "jacobian",
    "hessian",
    "m",
    "dm/dq",
    "dm/dq relative",
    "pose (Pinocchio)",
    "J (Pinocchio)",
)


def accuracy(name: str, draws: int = 20) -> dict[str, float]:
    path, base, tip = suite.robot(name)
    read = read_urdf(path, base, tip)
    arm = SerialArm.from_chain(read.chain)
    joints = ref.chain(path, read.base_link, read.tip_link)
    rng = np.random.default_rng(0)
    rows = slice(None) if arm.n >= 6 else slice(0, 3)
    axes = "all" if arm.n >= 6 else "trans"
    worst = dict.fromkeys(QUANTITIES, 0.0)
    for _ in range(draws):
        q = suite.random_q(arm, rng)
        T, J = ref.forward(joints, q)
        T_pin, J_pin = suite.pinocchio_reference(
            path, read.base_link, read.tip_link, read.chain.names, q
        )
        m, Jm = arm.manipulability_and_jacobian(q, axes)
        exact = ref.manipulability_gradient(joints, q, rows)
        relative = np.abs(Jm - exact).max() / max(np.abs(exact).max(), 1e-300)
        worst["dm/dq relative"] = max(worst.get("dm/dq relative", 0.0), float(relative))
        found = {
            "pose": np.abs(arm.forward(q) - T).max(),
            "jacobian": np.abs(arm.jacobian(q) - J).max(),
            "hessian": np.abs(arm.hessian(q) - ref.hessian(joints, q)).max(),
            "m": abs(m - ref.manipulability(joints, q, rows)),
            "dm/dq": np.abs(Jm - exact).max(),
            "pose (Pinocchio)": np.abs(arm.forward(q) - T_pin).max(),
            "J (Pinocchio)": np.abs(arm.jacobian(q) - J_pin).max(),
        }
        for key, value in found.items():
            worst[key] = max(worst[key], float(value))
    return {"joints": arm.n, "prismatic": int(read.chain.prismatic.sum()), **worst}


def loading(repeats: int = 20) -> dict[str, float]:
    path, base, tip = suite.robot("panda")
    data = load_scenario("panda").to_dict()
    data["arm"] = {"urdf": str(path), "base_link": base, "tip_link": tip}
    cold = subprocess.run(
        [
            sys.executable,
            "-c",
            "import time; t = time.perf_counter(); from emdm.core.urdf import read_urdf; "
            "u = time.perf_counter(); "
            f"read_urdf({str(path)!r}, {base!r}, {tip!r}); "
            "print(u - t, time.perf_counter() - u)",
        ],
        capture_output=True,
        text=True,
        check=True,
    )
    return {
        "read_urdf_s": _median_time(lambda: read_urdf(path, base, tip), repeats),
        "scenario_s": _median_time(lambda: scenario_from_dict(data, source="bench"), repeats),
        "cold_process_import_emdm_s": float(cold.stdout.split()[0]),
        "cold_process_first_read_s": float(cold.stdout.split()[1]),
    }


def per_step(repeats: int = 31) -> dict[str, float]:
    path, base, tip = suite.robot("panda")
    dh = load_scenario("panda")
    data = dh.to_dict()
    data["arm"] = {"urdf": str(path), "base_link": base, "tip_link": tip}
    urdf = scenario_from_dict(data, source="bench")
    same = dh.with_overrides(
        {f"arm.{k}": getattr(urdf.arm, k).tolist() for k in ("q_min", "q_max", "qd_min", "qd_max")}
    )
    a, b = emdm.simulate(urdf, "C-EMDM"), emdm.simulate(same, "C-EMDM")  # compiled, warm
    assert a.q.shape == b.q.shape
    steps = a.q.shape[0] - 1
    times: dict[str, list[float]] = {"urdf": [], "dh": []}
    for _ in range(repeats):  # alternately, so drifts of the machine touch both alike
        for key, sc in (("urdf", urdf), ("dh", same)):
            start = time.perf_counter()
            emdm.simulate(sc, "C-EMDM")
            times[key].append(time.perf_counter() - start)
    us = {key: 1e6 * statistics.median(v) / steps for key, v in times.items()}
    return {
        "steps": steps,
        "largest_difference_in_q": float(np.abs(a.q - b.q).max()),
        "urdf_us_per_step": us["urdf"],
        "dh_us_per_step": us["dh"],
        "ratio": us["urdf"] / us["dh"],
    }


def table(out: dict) -> str:
    lines = [
        "Largest error over 20 random configurations per robot (numpy reference of URDF's "
        f"semantics, complex steps for H, 40 digits for m and dm/dq; Pinocchio {out['pinocchio']}):",
        "",
        "| robot | joints | " + " | ".join(QUANTITIES) + " |",
        "|---|---:|" + "---:|" * len(QUANTITIES),
    ]
    for name, row in out["accuracy"].items():
        cells = " | ".join(f"{row[q]:.1e}" for q in QUANTITIES)
        lines.append(f"| {name} | {row['joints']} | {cells} |")
    load, step = out["loading"], out["per_step"]
    lines += [
        "",
        f"Loading the Panda's URDF (medians, warm process): read_urdf {1e3 * load['read_urdf_s']:.1f}"
        f" ms, a scenario naming it {1e3 * load['scenario_s']:.1f} ms; in a new process, after "
        f"importing emdm ({load['cold_process_import_emdm_s']:.2f} s, every command pays it), the "
        f"first read (importing yourdfpy and trimesh) {load['cold_process_first_read_s']:.2f} s.",
        "",
        f"Per step, Panda C-EMDM pose task ({step['steps']} steps, medians over 31 alternating "
        f"repeats): URDF {step['urdf_us_per_step']:.2f} us, DH {step['dh_us_per_step']:.2f} us, "
        f"ratio {step['ratio']:.3f}; largest difference in q between the two runs "
        f"{step['largest_difference_in_q']:.1e} rad.",
        "",
        "| target | measured |",
        "|---|---:|",
        f"| 7-joint URDF arm per step <= 1.10 x DH | {step['ratio']:.3f} x |",
        f"| loading a URDF < 0.5 s | {load['cold_process_first_read_s']:.2f} s cold, "
        f"{1e3 * load['read_urdf_s']:.1f} ms warm |",
        f"| every quantity within 1e-12 of both references | "
        f"{max(max(row[q] for q in QUANTITIES) for row in out['accuracy'].values()):.1e} |",
        "",
        "dm/dq relative: the largest error over the largest |dm/dq| of the same configuration. "
        "Away from singularities the kernel evaluates dm/dq with a Householder factor of J_a^T "
        "(docs/mathematics.md, 'Spatial arms'), near one from the SVD.",
        "",
        f"Machine: {out['machine']}.",
    ]
    return "\n".join(lines)


def main() -> int:
    out = {
        "pinocchio": pin.__version__,
        "accuracy": {name: accuracy(name) for name in suite.ROBOTS},
        "loading": loading(),
        "per_step": per_step(),
        "machine": f"{platform.platform()}, Python {platform.python_version()}, "
        f"numpy {np.__version__}",
    }
    (HERE / "urdf.json").write_text(json.dumps(out, indent=2) + "\n", encoding="utf-8")
    text = table(out)
    (HERE / "urdf.md").write_text(text + "\n", encoding="utf-8")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
