"""Benchmark of ``railmbs.study`` (not a test): a 16-case study of
Manchester Vehicle 1 on track case 1 (the primary longitudinal stiffness of
both bogies over 16 nearby values, so that every case costs about the same,
as ``tools/study-bench``), run on the local pool and on a 2-worker Dask
``LocalCluster``, against 16 × the wall time of one single run of a case
measured in the same invocation.

    python python/bench/study_bench.py [--end-time 42] [--jobs 2] [--workers 2]

Reports, for each backend: the study's wall time; the parallel efficiency
16·T1 / (P·T_study) (T1 the single run's wall time, P the threads or
workers); the per-case overhead: the CPU of a case beyond its integration
(scenario set-up, engine state, the static equilibrium the scenario starts
from, reductions) and the wall time beyond the cases across
the study (P·T_study − Σ case wall time, per case: scheduling, pickling,
result handling, waiting); the plugin derivations and compilations (client
and workers). The Dask cluster's start-up is reported apart (it is paid once
per cluster, not per study). The machine may be shared: compare the numbers
of one invocation, and repeat.
"""

from __future__ import annotations

import argparse
import os
import shutil
import tempfile
import time
from pathlib import Path

# Imported here, not inside the first timed study: the result table of
# either backend is a DataFrame, and pandas' first import (about 0.5 s on a
# loaded machine) would otherwise be billed to whichever backend runs first.
import pandas  # noqa: F401

import railmbs
import railmbs.study as rs

REPO = Path(__file__).resolve().parents[2]
SCENARIO = REPO / "models" / "scenarios" / "vehicle1_tc1.ron"
KX = [31.0e6 + 0.05e6 * k for k in range(16)]

STUDY = """Study(
    scenario: "{scenario}",
    engine: Symbolic,
    end_time: Some({end_time}),
    set: {{ "Bogie1.kx": "{{kx}}", "Bogie2.kx": "{{kx}}" }},
    cases: Grid({{ "kx": [{kx}] }}),
    reductions: [Assessment, Max(column: "Bogie1.WS1.contact.L.Y [N]")],
)
"""


def report(name: str, df, wall: float, parallel: int, single: float, single_cpu: float) -> None:
    n = len(df)
    assert (df["status"] == "ok").all(), df[["index", "status", "error"]]
    # integration_time[s] is the runner's clock: the CPU time of the case's
    # thread (the wall-clock time where the platform has no thread clock),
    # as cpu_time[s]; their difference is the case's CPU beyond the
    # integration (scenario set-up, static equilibrium, reductions).
    inside = (df["cpu_time[s]"] - df["integration_time[s]"]).mean()
    across = (parallel * wall - df["wall_time[s]"].sum()) / n
    print(f"{name}: {n} cases in {wall:.2f} s on {parallel}; "
          f"efficiency 16·T1/(P·T) = {n * single / (parallel * wall):.1%}; "
          f"mean case wall {df['wall_time[s]'].mean():.3f} s, CPU {df['cpu_time[s]'].mean():.3f} s "
          f"(integration {df['integration_time[s]'].mean():.3f} s)")
    print(f"  per-case overhead: CPU of a case beyond its integration {1e3 * inside:.1f} ms; "
          f"wall beyond the cases (P·T − Σ case wall)/n {1e3 * across:.1f} ms")
    # CPU of the cases' threads against 16 single runs' CPU: what the study
    # costs beyond the runs themselves, whatever else the machine runs.
    cases_cpu = df["cpu_time[s]"].sum()
    print(f"  CPU of the cases {cases_cpu:.2f} s against 16 × single {n * single_cpu:.2f} s "
          f"(CPU efficiency {n * single_cpu / cases_cpu:.1%})")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--end-time", type=float, default=42.0, help="simulated time per case, s (the scenario's 42 by default)")
    ap.add_argument("--jobs", type=int, default=2, help="threads of the local pool")
    ap.add_argument("--workers", type=int, default=2, help="Dask worker processes (one thread each)")
    ap.add_argument("--fresh-cache", action="store_true",
                    help="start from an empty plugin cache (the client then compiles the plugin once)")
    args = ap.parse_args()
    print(f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f} "
          f"(shared machine: the numbers are noisy)")
    work = Path(tempfile.mkdtemp(prefix="study-bench-"))
    if args.fresh_cache:
        # Set before anything builds and before the workers start (they
        # inherit it): every plugin of this invocation is in here.
        os.environ["RAILMBS_CACHE_DIR"] = str(work / "cache")
    study = work / "bench.ron"
    study.write_text(STUDY.format(scenario=SCENARIO, end_time=args.end_time, kx=", ".join(f"{x:e}" for x in KX)))

    # The plugin once, through the cache (compiles only on a cold cache).
    t = time.perf_counter()
    _, eng = rs.engine(study)
    print(f"engine prepared in {time.perf_counter() - t:.2f} s: {eng.builds()} (cache {os.environ.get('RAILMBS_CACHE_DIR', 'default')})")

    # One single run of case 0 (a plain railmbs.run, in process, symbolic engine).
    t, c = time.perf_counter(), time.process_time()
    r = railmbs.run(SCENARIO, set={"Bogie1.kx": KX[0], "Bogie2.kx": KX[0]}, end_time=args.end_time, engine="symbolic")
    single, single_cpu = time.perf_counter() - t, time.process_time() - c
    print(f"single run: wall {single:.3f} s, CPU {single_cpu:.3f} s (integration {r.summary['cpu_time']:.3f} s); "
          f"16 × wall = {16 * single:.2f} s")

    t = time.perf_counter()
    df = rs.run(study, work / "local", jobs=args.jobs, progress=False)
    report("local pool", df, time.perf_counter() - t, args.jobs, single, single_cpu)

    from dask.distributed import Client, LocalCluster

    t = time.perf_counter()
    with LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                      host="127.0.0.1", dashboard_address=None) as cluster, Client(cluster) as client:
        print(f"Dask LocalCluster of {args.workers} workers started in {time.perf_counter() - t:.2f} s")
        t = time.perf_counter()
        df = rs.run(study, work / "dask", backend=client, progress=False)
        report("dask", df, time.perf_counter() - t, args.workers, single, single_cpu)
        builds = client.run(rs.worker_builds)
    compiled = eng.builds()["compiled"] + sum(b["compiled"] for bs in builds.values() for b in bs)
    derived = eng.builds()["derived"] + sum(b["derived"] for bs in builds.values() for b in bs)
    print(f"plugin: client {eng.builds()}; workers {[b for bs in builds.values() for b in bs]}")
    print(f"plugin compilations in total: {compiled} (derivations {derived})")
    print(f"load average at the end {os.getloadavg()[0]:.2f}")
    shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
