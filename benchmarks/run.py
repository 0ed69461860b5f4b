"""The benchmark harness: `python benchmarks/run.py` writes benchmarks/latest.{json,md}.

It runs `emdm bench` (see src/emdm/studies/bench.py): per-step cost split into kinematics, program
build, solve and integration on the reference path, the fast path and the standard stack (numpy
+ qpsolvers with daqp and quadprog, the same programs), whole-run times per preset and
controller, and batch throughput. Medians over repeats, warm-up excluded, all in one process.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from emdm.studies.bench import bench_table, run_bench


def main() -> int:
    here = Path(__file__).resolve().parent
    data = run_bench(progress=lambda message: print(f"  {message}", file=sys.stderr, flush=True))
    (here / "latest.json").write_text(json.dumps(data, indent=2) + "\n", encoding="utf-8")
    table = bench_table(data)
    (here / "latest.md").write_text(table + "\n", encoding="utf-8")
    print(table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
