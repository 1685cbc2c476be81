"""Studies from Python (railmbs.study): the local pool gives the table of
``umsim study`` for the same study file; a Dask LocalCluster (loopback)
gives the same table as the local pool; a killed worker and an interrupted
study lose no finished case and the study completes on resume with each case
run exactly once; a bad study file raises a located ModelError; the plugin
is built once per study and the workers compile nothing."""

from __future__ import annotations

import csv
import os
import signal
import subprocess
from pathlib import Path
from typing import Dict, List

import pytest

import railmbs
import railmbs.study as rs
from conftest import MODELS, SCENARIOS

# Columns measured in wall-clock or CPU time: they differ from run to run;
# every other cell is a number of the simulation and must match exactly.
TIMES = {"integration_time[s]", "cpu_time[s]", "wall_time[s]"}

# Five cases of the wheelset on springs at 30 m/s, 0.3 s each (~10 ms of
# CPU per case): four friction coefficients and one case whose value names
# no parameter (it fails: a row with its error, and the study goes on).
TINY = """Study(
    scenario: "{scenario}",
    end_time: Some(0.3),
    cases: Grid({{ "mu": [0.3, 0.35, 0.4, 0.45, "2 * no_such_parameter"] }}),
    reductions: [Assessment, Max(column: "contact.L.Y [N]"), Rms(column: "ws.y")],
)
"""

# A scenario of the same model (so the same plugin) whose cases each take
# about a second (max_step 20 µs over 3 s: ~1.5·10⁵ steps), so that a worker
# can be killed while it runs one.
SLOW_SCENARIO = """Scenario(
    model: "{model}",
    track: (file: "{track}", start: 10.0, speed: 30.0),
    parameters: {{ "v0": 30.0 }},
    end_time: 3.0,
    integrator: Park(rtol: 1e-5, atol: 1e-7, max_step: 2e-5),
    output: (interval: 0.01, bodies: ["ws"], forces: ["contact"]),
)
"""
SLOW = """Study(
    scenario: "slow_scenario.ron",
    cases: Grid({ "mu": [0.3, 0.35, 0.4, 0.45] }),
    reductions: [Assessment, Rms(column: "ws.y")],
)
"""


def write_tiny(folder: Path) -> Path:
    path = folder / "tiny.ron"
    path.write_text(TINY.format(scenario=SCENARIOS / "wheelset_on_springs_30.ron"))
    return path


def write_slow(folder: Path) -> Path:
    (folder / "slow_scenario.ron").write_text(
        SLOW_SCENARIO.format(
            model=MODELS / "vehicles" / "wheelset_on_springs.ron",
            track=MODELS / "tracks" / "straight.ron",
        )
    )
    path = folder / "slow.ron"
    path.write_text(SLOW)
    return path


def table(output_dir: Path) -> Dict[str, Dict[str, str]]:
    """results.csv parsed: case id → the row's cells (text) without the
    timing columns. The cells are the shortest round-trip texts Rust writes,
    so equal text is equal numbers."""
    with open(output_dir / "results.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    out = {}
    for r in rows:
        assert r["case_id"] not in out, f"case {r['case_id']} is in the table twice"
        out[r["case_id"]] = {k: v for k, v in r.items() if k not in TIMES}
    return out


def ids_in_file(output_dir: Path) -> List[str]:
    with open(output_dir / "results.csv", newline="") as f:
        return [r["case_id"] for r in csv.DictReader(f)]


@pytest.fixture(scope="module")
def study_dir(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("studies")


@pytest.fixture(scope="module")
def reference(study_dir, umsim) -> Dict[str, Dict[str, str]]:
    """The table of ``umsim study`` for the tiny study."""
    path = write_tiny(study_dir)
    out = study_dir / "cli"
    subprocess.run([str(umsim), "study", str(path), "-o", str(out), "--quiet"], check=True)
    return table(out)


@pytest.fixture(scope="module")
def client():
    """A real Dask cluster on the loopback interface: two worker processes
    of one thread each (the nannies restart a killed worker)."""
    distributed = pytest.importorskip("dask.distributed")
    cluster = distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address=None,
    )
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


def test_the_binding_lists_cases_header_and_runs_one_case(study_dir, reference):
    study = rs.load(write_tiny(study_dir))
    assert len(study) == 5 and study.variables == ["mu"] and study.engine == "symbolic"
    cases = study.cases()
    assert [c["index"] for c in cases] == list(range(5))
    assert cases[1]["inputs"] == {"mu": 0.35}
    assert cases[4]["inputs"] == {"mu": "2 * no_such_parameter"}
    assert set(reference) == {c["id"] for c in cases}
    header = study.result_header()
    assert header[:4] == ["index", "case_id", "mu", "status"]
    # One case by index and by id, on the engine alone: the CLI's row.
    eng = rs.StudyEngine.prepare(study)
    for key in (2, cases[2]["id"]):
        row = dict(zip(header, eng.run_case(key)))
        assert {k: v for k, v in row.items() if k not in TIMES} == reference[cases[2]["id"]]
    with pytest.raises(KeyError):
        eng.run_case(17)


def test_the_local_pool_gives_the_table_of_umsim_study(study_dir, reference, tmp_path):
    df = rs.run(write_tiny(study_dir), tmp_path, progress=False)
    assert table(tmp_path) == reference
    # The DataFrame is the table, in index order, failed case included.
    assert list(df["index"]) == list(range(5))
    assert list(df["status"]) == ["ok"] * 4 + ["failed"]
    assert "no_such_parameter" in df["error"][4] and df["error"][0] == ""
    assert df["YQ.max"][:4].notna().all() and df["YQ.max"][4:].isna().all()
    assert df.equals(rs.read_results(tmp_path))
    # Run again: everything is finished, nothing runs.
    seen = []
    rs.run(write_tiny(study_dir), tmp_path, progress=False, on_result=seen.append)
    assert seen == [] and len(ids_in_file(tmp_path)) == 5


def test_a_dask_local_cluster_gives_the_table_of_the_local_pool(study_dir, reference, client, tmp_path):
    seen = []
    df = rs.run(write_tiny(study_dir), tmp_path, backend=client, progress=True, on_result=seen.append)
    assert table(tmp_path) == reference
    assert len(seen) == 5 and len(df) == 5


def test_the_plugin_is_built_once_and_the_workers_compile_nothing(study_dir, client, tmp_path):
    path = write_tiny(study_dir)
    rs.run(path, tmp_path, backend=client, progress=False)
    _, eng = rs.engine(path)
    b = eng.builds()
    # Derived at most once (none when the plugin index knows the model),
    # compiled at most once (none on a cache hit), loaded once.
    assert b["derived"] + b["indexed"] == 1 and b["compiled"] <= 1 and b["loaded"] == 1, b
    per_worker = client.run(rs.worker_builds)
    assert len(per_worker) == 2
    for worker, engines in per_worker.items():
        mine = [e for e in engines if e["study"] == str(path)]
        # A worker that ran cases of this study loaded the client's plugin.
        for e in mine:
            assert (e["derived"], e["indexed"], e["compiled"], e["loaded"]) == (0, 0, 0, 1), (worker, e)
    assert sum(len([e for e in v if e["study"] == str(path)]) for v in per_worker.values()) >= 1


class Stop(Exception):
    """Raised by a callback to stop a study."""


@pytest.mark.parametrize("backend", ["local", "dask"])
@pytest.mark.parametrize("stop", [Stop, KeyboardInterrupt])
def test_an_interrupted_study_resumes_and_runs_each_case_once(study_dir, reference, request, tmp_path, backend, stop):
    be = "local" if backend == "local" else request.getfixturevalue("client")
    path = write_tiny(study_dir)
    first = []

    def stop_after_two(row):
        first.append(row["case_id"])
        if len(first) == 2:
            raise stop("enough")

    with pytest.raises(stop):
        rs.run(path, tmp_path, backend=be, jobs=1, progress=False, on_result=stop_after_two)
    recorded = ids_in_file(tmp_path)
    # The rows passed to the callback are in the table (a local case that
    # finished while the pool stopped may be recorded too, unannounced).
    assert first == recorded[: len(first)] and 2 <= len(recorded) < 5
    second = []
    rs.run(path, tmp_path, backend=be, progress=False, on_result=lambda r: second.append(r["case_id"]))
    assert sorted(recorded + second) == sorted(reference)
    assert table(tmp_path) == reference


def test_a_killed_worker_loses_no_finished_case(tmp_path, client):
    path = write_slow(tmp_path)
    local = tmp_path / "local"
    rs.run(path, local, jobs=2, progress=False)
    expected = table(local)
    assert all(r["status"] == "ok" for r in expected.values())

    killed = []

    def kill_a_busy_worker(row):
        if killed:
            return
        # A worker process with a case in flight is killed (SIGKILL, as on a
        # crash or the out-of-memory killer); its nanny starts a new one and
        # the scheduler gives the case to a live worker.
        busy = [w for w, keys in client.processing().items() if keys]
        if busy:
            pid = client.run(os.getpid, workers=[busy[0]])[busy[0]]
            killed.append((busy[0], list(client.processing()[busy[0]])))
            os.kill(pid, signal.SIGKILL)

    out = tmp_path / "dask"
    rs.run(path, out, backend=client, progress=False, on_result=kill_a_busy_worker)
    assert killed and killed[0][1], "no worker had a case in flight to kill"
    assert table(out) == expected
    # Every case once: the one that lost its worker is not recorded twice.
    assert sorted(ids_in_file(out)) == sorted(expected)
    client.wait_for_workers(2, timeout=60)


def test_a_bad_study_file_raises_a_located_model_error(tmp_path):
    bad = tmp_path / "bad.ron"
    bad.write_text(
        TINY.format(scenario=SCENARIOS / "wheelset_on_springs_30.ron").replace(
            'Max(column: "contact.L.Y [N]")', 'Max(colum: "contact.L.Y [N]")'
        )
    )
    with pytest.raises(railmbs.ModelError) as e:
        rs.run(bad, tmp_path / "out", progress=False)
    assert e.value.file == str(bad)
    assert e.value.line == 5 and e.value.column is not None
    assert "colum" in str(e.value)
    # Nothing was written for a study that did not load.
    assert not (tmp_path / "out").exists()
    empty = tmp_path / "empty.ron"
    empty.write_text(TINY.format(scenario="no_such_scenario.ron"))
    with pytest.raises(railmbs.ModelError) as e:
        rs.load(empty)
    assert "no_such_scenario.ron" in str(e.value)


def test_a_table_of_another_study_is_refused(study_dir, tmp_path):
    rs.run(write_tiny(study_dir), tmp_path, progress=False)
    other = write_slow(tmp_path)
    with pytest.raises(railmbs.StudyError, match="other columns"):
        rs.run(other, tmp_path, progress=False)


def test_ctrl_c_stops_the_local_pool_and_the_study_resumes(tmp_path, python_sigint_handler):
    path = write_slow(tmp_path)
    # SIGINT (Ctrl-C) when the first case has finished and others run (each
    # ~1 s): the running cases stop unrecorded, the finished ones stay. The
    # signal reaches Python's handler on the main thread, which polls it
    # while the pool runs with the GIL released.
    sent = []

    def interrupt_once(row):
        if not sent:
            sent.append(row["case_id"])
            os.kill(os.getpid(), signal.SIGINT)

    with pytest.raises(KeyboardInterrupt):
        rs.run(path, tmp_path / "out", jobs=2, progress=False, on_result=interrupt_once)
    before = ids_in_file(tmp_path / "out")
    assert sent[0] in before and len(before) < 4
    rest = []
    df = rs.run(path, tmp_path / "out", progress=False, on_result=lambda r: rest.append(r["case_id"]))
    assert sorted(before + rest) == sorted(c["id"] for c in rs.load(path).cases())
    assert list(df["status"]) == ["ok"] * 4


def test_a_worker_without_the_clients_plugin_file_builds_it_through_its_cache(study_dir, tmp_path):
    # Another machine without the shared cache: the shipped path does not
    # exist there, so the worker's engine is prepared through the cache
    # (once per process) instead of failing.
    path = write_tiny(study_dir)
    _, shipped = rs.engine(path)
    _, eng = rs.engine(path, [tmp_path / "elsewhere" / "plugin.so"])
    b = eng.builds()
    assert b["derived"] + b["indexed"] == 1 and b["loaded"] == 1
    assert eng.plugin_paths == shipped.plugin_paths
    # The worker's engine is cached: the same object on the next task.
    assert rs.engine(path, [tmp_path / "elsewhere" / "plugin.so"])[1] is eng
    # Another study of the same model loads the same plugin file; a wrong
    # number of plugin files is refused.
    other = rs.load(write_slow(tmp_path))
    assert rs.StudyEngine.from_plugins(other, shipped.plugin_paths).builds()["loaded"] == 1
    with pytest.raises(railmbs.PluginError, match="plugin file"):
        rs.StudyEngine.from_plugins(other, [])


# Two cases of the tiny study with their time series, in either format.
SERIES = """Study(
    scenario: "{scenario}",
    end_time: Some(0.3),
    cases: Grid({{ "mu": [0.3, 0.4] }}),
    reductions: [Max(column: "contact.L.Y [N]")],
    time_series: true,
    series_format: {format},
)
"""


def test_parquet_time_series_equal_the_csv_time_series_bit_for_bit(tmp_path, request):
    """The Parquet file of a case, read back with pyarrow, holds the CSV's
    columns (names and order) and values bit for bit; a Dask worker writes
    the same file as the local pool."""
    import numpy as np

    pq = pytest.importorskip("pyarrow.parquet")
    paths = {}
    for fmt in ("Csv", "Parquet"):
        paths[fmt] = tmp_path / f"{fmt}.ron"
        paths[fmt].write_text(SERIES.format(scenario=SCENARIOS / "wheelset_on_springs_30.ron", format=fmt))
    assert rs.load(paths["Parquet"]).series_format == "parquet"
    assert rs.load(paths["Csv"]).series_format == "csv"
    rs.run(paths["Csv"], tmp_path / "csv", progress=False)
    rs.run(paths["Parquet"], tmp_path / "pq", progress=False)
    ids = [c["id"] for c in rs.load(paths["Csv"]).cases()]
    for case_id in ids:
        with open(tmp_path / "csv" / "series" / f"{case_id}.csv", newline="") as f:
            rows = list(csv.reader(f))
        header, body = rows[0], rows[1:]
        # Python's float() of Rust's shortest round-trip text is the written double.
        expected = np.array([[float(x) for x in r] for r in body]).T
        t = pq.read_table(tmp_path / "pq" / "series" / f"{case_id}.parquet")
        assert t.column_names == header
        assert t.num_rows == len(body) > 10
        for k, name in enumerate(header):
            got = t.column(name).to_numpy()
            assert got.dtype == np.float64
            assert np.array_equal(got.view(np.uint64), expected[k].view(np.uint64)), name
        # read_series gives the same frame from either file.
        a, b = rs.read_series(tmp_path / "csv", case_id), rs.read_series(tmp_path / "pq", case_id)
        assert list(a.columns) == header and a.equals(b)
    # A Dask worker writes the same Parquet files.
    client = request.getfixturevalue("client")
    rs.run(paths["Parquet"], tmp_path / "dask", backend=client, progress=False)
    for case_id in ids:
        mine = (tmp_path / "dask" / "series" / f"{case_id}.parquet").read_bytes()
        assert mine == (tmp_path / "pq" / "series" / f"{case_id}.parquet").read_bytes()
