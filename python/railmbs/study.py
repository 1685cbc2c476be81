"""Parameter studies from Python: the study files of ``umsim study``, run on
a local pool of threads or on a Dask cluster.

A study file (``Study(...)``, RON; the format is documented in the
``railmbs-study`` crate: ``cargo doc -p railmbs-study --open``) lists the
cases of one scenario and what each is reduced to. :func:`run` runs the
cases that its output folder does not hold yet and returns the result
table::

    import railmbs.study
    df = railmbs.study.run("models/studies/vehicle1_yaw_speed.ron", "out/yaw")

    # the same on a Dask cluster (LocalCluster, SSHCluster, dask-jobqueue…)
    from dask.distributed import Client, LocalCluster
    with LocalCluster(n_workers=2, threads_per_worker=1) as cluster, Client(cluster) as client:
        df = railmbs.study.run("models/studies/vehicle1_yaw_speed.ron", "out/yaw", backend=client)

The table (``OUTPUT/results.csv``, the same file ``umsim study`` writes and
resumes) has one row per case: ``index``, ``case_id``, the variables,
``status`` (``ok``/``failed``), ``error``, ``steps``, ``rejected_steps``,
``t_end[s]`` (simulated time reached), ``integration_time[s]`` (CPU time of
the integration), ``cpu_time[s]`` (CPU time of the case: set-up, run,
reductions), ``wall_time[s]`` (wall-clock time of the case), then the
reductions (SI units, named in the column headers). Each row is appended (and flushed) as its case
finishes, so nothing finished is lost when the study is interrupted or a
worker dies; running :func:`run` again skips the finished case ids. A case
that fails (diverges, a bad parameter value) is a row with its error; it does
not stop the study.

**The plugin is compiled once per study.** The model's parameters are runtime
inputs of its compiled plugin: the local pool shares one loaded plugin among
its threads; with Dask the client builds the plugin (through the
content-hash cache) before it submits anything and sends the plugin's file
path with every task. Each worker process loads it once (its engine is
cached per process, keyed by the study file and the plugin paths) and never
compiles.

**A cluster of several machines** needs, on every machine, at the same
absolute paths: the study file with the scenario, model, track and profile
files it names (a shared file system, or the same checkout), and the
``railmbs`` package of the same version. The plugin file is found at the
client's path when the cache directory is shared too (``cache_dir`` on a
shared file system, or ``$RAILMBS_CACHE_DIR`` pointing there); a worker that
does not find it builds the plugin into its own cache once per worker
process (a few seconds to a minute, depending on the model). A plugin is
compiled for the CPU of the machine that built it (``-C target-cpu=native``),
so a shared cache needs machines of one CPU type. The result table is
written only by the client, in ``output_dir`` on the client's machine.
"""

from __future__ import annotations

import os
import uuid
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

from ._railmbs import ResultStore, Study, StudyEngine
from .errors import RailmbsError, StudyError

__all__ = [
    "ResultStore",
    "Study",
    "StudyEngine",
    "engine",
    "load",
    "read_results",
    "read_series",
    "run",
    "run_case",
    "worker_builds",
]

_PathLike = Union[str, "os.PathLike[str]"]

#: The result table's file in an output folder.
RESULTS = "results.csv"

# The engines of this process, one per study file (and its modification
# time), plugin paths and cache folder: a Dask worker process prepares each
# study's engine once and runs all its tasks of that study on it.
_ENGINES: Dict[Tuple[str, int, Tuple[str, ...], Optional[str]], Tuple[Study, StudyEngine]] = {}


def load(path: _PathLike) -> Study:
    """Reads and checks a study file, its scenario and model(s). Raises
    :class:`railmbs.ModelError` (file, element, line, column) for a bad one."""
    return Study.load(str(path))


def engine(
    study_path: _PathLike,
    plugin_paths: Optional[Sequence[_PathLike]] = None,
    cache_dir: Optional[_PathLike] = None,
) -> Tuple[Study, StudyEngine]:
    """The study of ``study_path`` and its engine, made once per process and
    cached. ``plugin_paths`` (one per model, as the client's
    ``StudyEngine.plugin_paths``): load those plugins, compiling nothing; if
    one is missing here (another machine without the shared cache), or for
    ``None`` or an empty list, the plugin is built through the cache
    (``cache_dir``, else ``$RAILMBS_CACHE_DIR``, else the platform cache
    folder)."""
    path = os.path.abspath(os.fspath(study_path))
    plugins = tuple(os.fspath(p) for p in plugin_paths or ())
    cache = None if cache_dir is None else os.fspath(cache_dir)
    key = (path, os.stat(path).st_mtime_ns, plugins, cache)
    found = _ENGINES.get(key)
    if found is None:
        study = Study.load(path)
        if plugins and all(os.path.exists(p) for p in plugins):
            eng = StudyEngine.from_plugins(study, list(plugins))
        else:
            eng = StudyEngine.prepare(study, cache)
        found = _ENGINES[key] = (study, eng)
    return found


def run_case(
    study_path: _PathLike,
    case: Union[int, str],
    plugin_paths: Optional[Sequence[_PathLike]] = None,
    cache_dir: Optional[_PathLike] = None,
    series_dir: Optional[_PathLike] = None,
) -> List[str]:
    """Runs one case (its index or id) of a study on this process's cached
    engine (:func:`engine`) and returns its row: the result table's cells
    as text, in ``Study.result_header()`` order. This is the task a Dask
    worker runs; the GIL is released during the run."""
    _, eng = engine(study_path, plugin_paths, cache_dir)
    return eng.run_case(case, None if series_dir is None else os.fspath(series_dir))


def worker_builds() -> List[Dict[str, Any]]:
    """The build counters (``derived``, ``indexed``, ``compiled``,
    ``loaded``) of every engine cached in this process, with its study file
    (``study``): ``client.run(railmbs.study.worker_builds)`` shows that the
    workers compiled nothing."""
    out = []
    for (path, _, _, _), (_, eng) in _ENGINES.items():
        b = dict(eng.builds())
        b["study"] = path
        out.append(b)
    return out


def read_results(output_dir: _PathLike) -> Any:
    """The result table of the study run into ``output_dir``
    (``output_dir/results.csv``) as a pandas DataFrame, one row per case in
    index order. ``case_id``, ``status`` and ``error`` are strings (``error``
    empty for a case that ran); numbers are floats or ints (times in s);
    an empty reduction (a failed case) is NaN."""
    import pandas as pd

    path = Path(output_dir) / RESULTS
    df = pd.read_csv(path, dtype={"case_id": str, "status": str, "error": str})
    df["error"] = df["error"].fillna("")
    return df.sort_values("index", kind="stable").reset_index(drop=True)


def read_series(output_dir: _PathLike, case_id: str) -> Any:
    """The time series of case ``case_id`` of the study run into
    ``output_dir`` (a study with ``time_series: true``) as a pandas
    DataFrame, one column per output column (the names of the CSV header,
    units in brackets), one row per output row: ``series/<case id>.parquet``
    (read with pyarrow) or ``series/<case id>.csv``, whichever is there.
    The values are the computed floats exactly, in either format."""
    import pandas as pd

    folder = Path(output_dir) / "series"
    parquet = folder / f"{case_id}.parquet"
    if parquet.exists():
        import pyarrow.parquet as pq

        return pq.read_table(parquet).to_pandas()
    # Every column is a float (a whole number such as "30" too). Before
    # pandas 3 the default parser may be an ulp off the shortest round-trip
    # text Rust writes; "round_trip" reads it exactly (pandas 3 does so by
    # default and deprecates the option).
    exact = {} if int(pd.__version__.split(".")[0]) >= 3 else {"float_precision": "round_trip"}
    return pd.read_csv(folder / f"{case_id}.csv", dtype="float64", **exact)


class _Progress:
    """A tqdm bar of the cases done and failed with its ETA (nothing when
    tqdm is not installed or ``enabled`` is false)."""

    def __init__(self, enabled: bool, total: int, name: str) -> None:
        self.failed = 0
        self.bar = None
        if enabled and total > 0:
            try:
                from tqdm.auto import tqdm
            except ImportError:
                return
            self.bar = tqdm(total=total, desc=name, unit="case", dynamic_ncols=True)
            self.bar.set_postfix(failed=0)

    def update(self, failed: bool) -> None:
        self.failed += int(failed)
        if self.bar is not None:
            self.bar.update(1)
            if failed:
                self.bar.set_postfix(failed=self.failed)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def run(
    study_path: _PathLike,
    output_dir: _PathLike,
    backend: Any = "local",
    jobs: Optional[int] = None,
    progress: bool = True,
    cache_dir: Optional[_PathLike] = None,
    on_result: Optional[Callable[[Dict[str, str]], None]] = None,
) -> Any:
    """Runs the cases of a study that ``output_dir/results.csv`` does not
    hold yet and returns the whole result table (:func:`read_results`).

    ``backend``: ``"local"`` runs the cases on ``jobs`` threads of this
    process (``None``: one per core) sharing one loaded plugin, as ``umsim
    study`` does; a ``dask.distributed.Client`` submits one task per
    pending case to its cluster (``jobs`` is then unused: the workers'
    threads set the parallelism). Either way each row is appended to the
    table as its case finishes. ``progress``: a tqdm bar (cases, failed,
    ETA) when tqdm is installed. ``cache_dir``: the plugin cache (default
    ``$RAILMBS_CACHE_DIR``, else the platform cache folder).
    ``on_result(row)``: called with each recorded row (column → cell text);
    an exception it raises stops the study (running local cases stop
    unrecorded; Dask tasks not yet finished are cancelled, and a case
    already running on a worker ends there unrecorded) and propagates, as
    does Ctrl-C; the rows recorded stay, and the next :func:`run` resumes.
    A Dask worker that dies (killed, out of memory) loses only its running
    case, which the scheduler gives to another worker.

    Raises :class:`railmbs.ModelError` for a bad study file,
    :class:`railmbs.PluginError` when the plugin cannot be built,
    :class:`railmbs.StudyError` when the table belongs to another study, a
    reduction fits no output column, or (Dask) cases were lost with their
    workers more often than the scheduler retries them (run again to
    resume them).
    """
    study_path = os.path.abspath(os.fspath(study_path))
    out = Path(output_dir)
    study = Study.load(study_path)
    header = study.result_header()
    store = ResultStore.open(str(out / RESULTS), header)
    finished = store.finished()
    pending = [c for c in study.cases() if c["id"] not in finished]
    status = header.index("status")
    bar = _Progress(progress, len(pending), Path(study_path).stem)

    def record(row: Sequence[str]) -> None:
        bar.update(row[status] == "failed")
        if on_result is not None:
            on_result(dict(zip(header, row)))

    try:
        if pending:
            if isinstance(backend, str):
                if backend != "local":
                    raise ValueError(
                        f"backend is \"local\" or a dask.distributed.Client, not {backend!r}"
                    )
                _, eng = engine(study_path, None, cache_dir)
                eng.run_local(store, jobs or 0, record)
            else:
                _run_dask(backend, study, study_path, out, store, pending, cache_dir, record)
    finally:
        bar.close()
    return read_results(out)


def _run_dask(
    client: Any,
    study: Study,
    study_path: str,
    out: Path,
    store: ResultStore,
    pending: List[Dict[str, Any]],
    cache_dir: Optional[_PathLike],
    record: Callable[[Sequence[str]], None],
) -> None:
    """The Dask backend of :func:`run`: the plugin built here once, one task
    per pending case, each row appended as its task completes."""
    from dask.distributed import as_completed

    # Built (or found in the cache) here, before any task: the workers load
    # this file and compile nothing.
    _, eng = engine(study_path, None, cache_dir)
    plugins = [os.fspath(p) for p in eng.plugin_paths]
    cache = None if cache_dir is None else os.fspath(cache_dir)
    series = os.fspath(out.resolve() / "series") if study.time_series else None
    token = uuid.uuid4().hex[:8]
    futures = [
        client.submit(
            run_case,
            study_path,
            c["id"],
            plugins,
            cache,
            series,
            key=f"railmbs-case-{c['index']}-{c['id']}-{token}",
        )
        for c in pending
    ]
    lost: List[str] = []
    try:
        for fut in as_completed(futures):
            try:
                row = fut.result()
            except (RailmbsError, KeyboardInterrupt):
                # A fault of the study itself (the same for every case).
                raise
            except Exception as e:  # noqa: BLE001: the worker died (KilledWorker), or the task was lost
                lost.append(f"{fut.key}: {type(e).__name__}: {e}")
                continue
            store.append(row)
            record(row)
    finally:
        # Stopped early (an exception, Ctrl-C): nothing more is started.
        unfinished = [f for f in futures if not f.done()]
        if unfinished:
            client.cancel(unfinished)
    if lost:
        raise StudyError(
            f"{len(lost)} case(s) were not run: their workers died more often than the "
            f"scheduler retries a task ({'; '.join(lost[:3])}{'…' if len(lost) > 3 else ''}); "
            f"the finished cases are in {store.path}; run the study again to resume"
        )
