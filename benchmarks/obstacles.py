"""Obstacles: `python benchmarks/obstacles.py` writes benchmarks/obstacles.{json,md}.

The speed of the obstacle rows (5 circles on task1's arm, 10 spheres on the Panda, a planar batch)
and the random-scene benchmark of docs/mathematics.md, "Obstacles" (src/emdm/studies/obstacle_bench.py):
C-EMDM and NEO against the same controllers blind to the obstacles, seeded, with 95 % Wilson
intervals. Medians over repeats, all in one process.
"""

from __future__ import annotations

import json
import platform
import sys
from pathlib import Path

import numba
import numpy as np
import scipy

from emdm.studies.obstacle_bench import never_entered, obstacle_speed, random_scenes

SCENES = {"obstacle": (400, 3, (0.03, 0.10)), "panda-obstacles": (150, 4, (0.02, 0.06))}
"""Per preset: scenes, obstacles per scene, radius range (m)."""


MACHINE = (
    f"{platform.platform()}, Python {platform.python_version()}, numpy {np.__version__}, "
    f"scipy {scipy.__version__}, numba {numba.__version__}"
)


def table(speed: dict, studies: list[dict], guard: dict, machine: str) -> str:
    lines = ["Speed (C-EMDM through emdm.simulate, medians):", ""]
    lines += ["| scene | steps | rows per step | us/step |", "|---|---:|---:|---:|"]
    for key in ("planar_5_circles", "panda_10_spheres"):
        r = speed[key]
        lines.append(
            f"| {key.replace('_', ' ')} | {r['steps']} | {r['rows_per_step']:.1f} | "
            f"{r['us_per_step']:.2f} |"
        )
    b = speed["batch"]
    lines += [
        "",
        f"Batch (preset `obstacle`, C-EMDM, {b['runs']} random reachable goals): "
        f"{b['steps']} steps in {b['seconds']:.3f} s = {b['steps_per_second']:.3g} steps/s; "
        f"{b['handed_to_the_chain']} runs finished by the solver chain.",
        "",
    ]
    lines += [
        f"Never entered (`{guard['preset']}` arm, 50 random scenes x 200 random reachable goals, "
        f"C-EMDM through the batch loop): {guard['runs']} runs, {guard['reached']} reached; "
        f"smallest clearance {guard['min_clearance']!r} m against a stop distance of "
        f"{guard['stop']} m; {guard['runs_inside_stop']} runs ever inside it by more than 1e-12 m; "
        f"{guard['runs_finished_by_the_chain']} runs finished by the solver chain, "
        f"{guard['runs_stopped']} stopped without an admissible command.",
        "",
    ]
    for st in studies:
        proved = st.get("proved_solvable")
        lines += [
            f"Random scenes on `{st['preset']}` ({st['scenes']} scenes, {st['obstacles']} "
            f"obstacles each, radius uniform in {st['radius'][0]}-{st['radius'][1]} m, "
            f"centres uniform along the straight path of the end effector plus an offset uniform "
            f"within 0.3 of its length, seed {st['seed']}; success = reached and "
            "never inside the stop distance):",
            "",
        ]
        head = (
            "| controller | success | 95 % CI | collisions | 95 % CI | stopped | "
            "median min clearance (m) | median time to goal (s) | mean m |"
        )
        rule = "|---|---:|---:|---:|---:|---:|---:|---:|---:|"
        if proved is not None:
            head += " success where proved solvable | 95 % CI |"
            rule += "---:|---:|"
        lines += [head, rule]
        for name, r in st["controllers"].items():
            row = (
                f"| {name} | {r['success']:.3f} | {r['success_ci'][0]:.3f}-{r['success_ci'][1]:.3f} "
                f"| {r['collisions']:.3f} | {r['collisions_ci'][0]:.3f}-{r['collisions_ci'][1]:.3f} "
                f"| {r['stopped']:.3f} | {r['min_clearance_median']:.4f} | "
                f"{r['time_to_goal_median']:.2f} | {r['mean_manipulability']:.4f} |"
            )
            if proved is not None:
                ci = r["success_proved_ci"]
                row += f" {r['success_proved']:.3f} | {ci[0]:.3f}-{ci[1]:.3f} |"
            lines.append(row)
        lines.append("")
        if st["emdm_equals_neo"]:
            lines += [
                "C-EMDM and NEO solve one program in a scene with obstacles (the task with its "
                "slack, effort, manipulability, joint bounds and dampers, obstacle rows; the "
                "optional centring and clearance terms are off by default), and their runs here "
                "are identical in every scene. `C-EMDM task held` is the brief's C-EMDM, whose "
                "slack serves only a non-redundant arm: the evidence for the slack.",
                "",
            ]
        if proved is not None:
            lines += [
                f"Proved solvable: {proved} of {st['scenes']} scenes have a collision-free "
                "motion from the start to a goal configuration, found on a grid of "
                f"{st['proof_cells']} cells per joint whose cells keep every link d_s plus a margin (up to "
                f"{max(st['proof_margin']):.3f} m for the last link) away, so that every "
                "configuration between "
                "adjacent cell centres keeps d_s (src/emdm/studies/solvable.py). A scene whose "
                "only passage is narrower than the margins is not proved: the count is a lower "
                "bound. Successes in scenes not proved: "
                + ", ".join(f"{n} {r['success_not_proved']}" for n, r in st["controllers"].items())
                + ".",
                "",
            ]
    lines.append(f"Machine: {machine}.")
    return "\n".join(lines)


def main() -> int:
    here = Path(__file__).resolve().parent
    speed = obstacle_speed()
    studies = [random_scenes(p, n, k, r, prove=p == "obstacle") for p, (n, k, r) in SCENES.items()]
    guard = never_entered()
    machine = MACHINE
    out = {"speed": speed, "scenes": studies, "never_entered": guard, "machine": machine}
    (here / "obstacles.json").write_text(json.dumps(out, indent=2) + "\n", encoding="utf-8")
    text = table(speed, studies, guard, machine)
    (here / "obstacles.md").write_text(text + "\n", encoding="utf-8")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
