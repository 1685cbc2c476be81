"""Per-call overhead of ``Scenario.run()`` against a whole ``umsim run``
process, for a short model (a benchmark, not a test).

    python python/bench/overhead.py [--scenario models/scenarios/double_pendulum.ron]
        [--end-time 0.01] [--repeat 30] [--umsim target/release/umsim]

For each engine it reports the wall time per call of ``run()`` (scenario
already loaded; a fresh copy per call, as a study would make), the part of
it the runner spent integrating (the summary's CPU time) and the rest (the
overhead: model copy, engine set-up — for the symbolic engine deriving the
equations to find the plugin in the cache and loading it — output columns,
numpy arrays), against the wall time of ``umsim run SCENARIO --end-time T -q
-o FILE`` as a process (start-up, reading files, the same run, CSV).
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import railmbs

REPO = Path(__file__).resolve().parents[2]


def timed(f, repeat: int):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), min(times), out


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scenario", default=str(REPO / "models/scenarios/double_pendulum.ron"))
    p.add_argument("--end-time", type=float, default=0.01)
    p.add_argument("--repeat", type=int, default=30)
    p.add_argument("--umsim", default=str(REPO / "target/release/umsim"))
    args = p.parse_args()

    base = railmbs.Scenario.load(args.scenario)
    base.end_time = args.end_time
    print(f"{args.scenario}, end time {args.end_time} s, median (min) of {args.repeat} calls")
    print(f"{'':24} {'wall/call':>12} {'integration':>12} {'overhead':>12}")
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out.csv"
        for engine in ["numeric", "symbolic"]:
            base.copy().run(engine=engine)  # warm: plugin built or found in the cache
            med, best, r = timed(lambda: base.copy().run(engine=engine), args.repeat)
            cpu = r.summary["cpu_time"]
            print(f"{'run() ' + engine:24} {med * 1e3:9.2f} ms {cpu * 1e3:9.2f} ms {(med - cpu) * 1e3:9.2f} ms   (min {best * 1e3:.2f} ms)")
            cmd = [args.umsim, "run", args.scenario, "--engine", engine, "--end-time", str(args.end_time), "-q", "-o", str(out)]
            subprocess.run(cmd, check=True)
            med_cli, best_cli, _ = timed(lambda: subprocess.run(cmd, check=True), args.repeat)
            print(f"{'umsim run ' + engine:24} {med_cli * 1e3:9.2f} ms {'':12} {'':12}   (min {best_cli * 1e3:.2f} ms)")


if __name__ == "__main__":
    main()
