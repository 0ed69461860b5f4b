"""Obstacles: `python benchmarks/obstacles.py` writes benchmarks/obstacles.{json,md}.

The speed of the obstacle rows (5 circles on task1's arm, 10 spheres on the Panda, a planar batch)
and the random-scene benchmark of docs/mathematics.md, "Obstacles" (src/emdm/studies/obstacle_bench.py):
C-EMDM and NEO against the same controllers blind to the obstacles, seeded, with 95 % Wilson
intervals. Medians over repeats, all in one process.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from emdm.studies.obstacle_bench import never_entered, obstacle_speed, random_scenes

SCENES = {"obstacle": (400, 3, (0.03, 0.10)), "panda-obstacles": (150, 4, (0.02, 0.06))}
"""Per preset: scenes, obstacles per scene, radius range (m)."""


def table(speed: dict, studies: list[dict], guard: dict) -> str:
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
        lines += [
            f"Random scenes on `{st['preset']}` ({st['scenes']} scenes, {st['obstacles']} "
            f"obstacles each, radius uniform in {st['radius'][0]}-{st['radius'][1]} m, "
            f"centres uniform along the straight path of the end effector plus an offset uniform "
            f"within 0.3 of its length, seed {st['seed']}; success = reached and "
            "never inside the stop distance):",
            "",
            "| controller | success | 95 % CI | collisions | 95 % CI | stopped | "
            "median min clearance (m) | median time to goal (s) | mean m |",
            "|---|---:|---:|---:|---:|---:|---:|---:|---:|",
        ]
        for name, r in st["controllers"].items():
            lines.append(
                f"| {name} | {r['success']:.3f} | {r['success_ci'][0]:.3f}-{r['success_ci'][1]:.3f} "
                f"| {r['collisions']:.3f} | {r['collisions_ci'][0]:.3f}-{r['collisions_ci'][1]:.3f} "
                f"| {r['stopped']:.3f} | {r['min_clearance_median']:.4f} | "
                f"{r['time_to_goal_median']:.2f} | {r['mean_manipulability']:.4f} |"
            )
        lines.append("")
    return "\n".join(lines)


def main() -> int:
    here = Path(__file__).resolve().parent
    speed = obstacle_speed()
    studies = [random_scenes(p, n, k, r) for p, (n, k, r) in SCENES.items()]
    guard = never_entered()
    (here / "obstacles.json").write_text(
        json.dumps({"speed": speed, "scenes": studies, "never_entered": guard}, indent=2) + "\n",
        encoding="utf-8",
    )
    text = table(speed, studies, guard)
    (here / "obstacles.md").write_text(text + "\n", encoding="utf-8")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
