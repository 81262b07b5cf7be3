"""Shared test fixtures and helpers."""

from __future__ import annotations

import os
from ctypes import byref
from pathlib import Path

import pytest
from fmpy.fmi1 import printLogMessage
from fmpy.fmi2 import fmi2CallbackFunctions, fmi2CallbackLoggerTYPE
from fmpy.logging import addLoggerProxy
from hypothesis import settings
from threadpoolctl import threadpool_limits

# No per-example deadline (a loaded 2-core machine makes timings noisy); in CI the examples are
# derandomised so that a run is reproducible.
settings.register_profile("default", deadline=None)
settings.register_profile("ci", deadline=None, derandomize=True)
settings.load_profile("ci" if os.environ.get("CI") else "default")

# One BLAS/OpenMP thread per test process. quickstart.sh runs one pytest-xdist worker per core, so
# with OpenBLAS' default (a thread per core) each worker's BLAS threads compete with the other
# workers' for the same cores, and OpenBLAS' threads spin while they wait: a small least-squares
# problem (identify's piecewise-linear fits, a few hundred samples) then took 5-10 times longer
# (measured: 4.9-7.1 s instead of 0.6-0.8 s for one identify on a 251-sample record, with another
# process busy on the second core). The library does the same where it runs such fits
# (pimodel.identify, pimodel.diagnosis.diagnose, pimodel.experiments.sweeps). Set before any
# test runs, and in the environment for the subprocesses the tests start (the CLI, the docs
# build, the studies).
THREAD_ENV = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
for _name in THREAD_ENV:
    os.environ[_name] = "1"
_BLAS_LIMIT = threadpool_limits(limits=1)


# fmpy's native logger proxy (fmpy/logging, addLoggerProxy) keeps the last logger it was given in
# one process-wide pointer, and simulate_fmu(logger=...) gives it a ctypes callback that is freed
# when the call returns (tests/test_estimator_fmu.py and the docs/estimator.md snippet do this).
# A later FMI 2 instance with fmpy's default callbacks that logs (FMU2Slave.instantiate(): e.g. a
# doStep that returns fmi2Error) then calls freed memory: a segfault or abort in whichever
# pytest-xdist worker ran both. After every test the pointer is set to this logger, alive for
# the whole process.
_PROCESS_LOGGER = fmi2CallbackLoggerTYPE(printLogMessage)


@pytest.fixture(autouse=True)
def fmpy_logger_proxy_restored():
    """After each test, fmpy's logger proxy calls a logger alive for the whole process."""
    yield
    callbacks = fmi2CallbackFunctions()
    callbacks.logger = _PROCESS_LOGGER
    addLoggerProxy(byref(callbacks))


REPO = Path(__file__).resolve().parents[1]
SHARED_DATA = REPO.parent / "shared" / "data" / "real" / "smarthysteresis-piezo-1hz"
REAL_RECORD = SHARED_DATA / "piezo_1hz.csv"


@pytest.fixture
def real_record_path() -> Path:
    """Path to the shared real piezo record; skips the test when ../shared is absent."""
    if not REAL_RECORD.exists():
        pytest.skip(f"shared real record not found at {REAL_RECORD} (needs ../shared beside "
                    "the repo)")
    return REAL_RECORD


@pytest.fixture(scope="session", autouse=True)
def fmu_build_cache(tmp_path_factory, worker_id):
    """One compile cache (``pimodel.fmu.build_cache``) for every FMU build of this run, in the
    run's temporary folder (common to the pytest-xdist workers), so that each object and binary
    is compiled once per run and no run depends on an earlier one. A ``PIMODEL_BUILD_CACHE``
    set before the run is kept (e.g. a cache kept between CI runs)."""
    from pimodel.fmu.build_cache import ENV_VAR, cache_dir

    if ENV_VAR in os.environ:
        yield cache_dir()
        return
    base = tmp_path_factory.getbasetemp()
    folder = (base if worker_id == "master" else base.parent) / "fmu_build_cache"
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv(ENV_VAR, str(folder))
        yield folder


@pytest.fixture(scope="session")
def built_fmus(tmp_path_factory, worker_id) -> Path:
    """Every FMU unit built once per run for FMI 2.0 and 3.0 into one folder (read only: tests
    that change an FMU copy it first). Under pytest-xdist the workers share it: the first
    builds it in the run's common temporary folder while the others wait on a lock (POSIX
    ``fcntl``; elsewhere each worker builds its own)."""
    from pimodel.fmu import build_fmus

    def build(out: Path) -> Path:
        out.mkdir(parents=True, exist_ok=True)
        build_fmus(out, fmi_version="2.0")
        build_fmus(out, fmi_version="3.0")
        return out

    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX
        fcntl = None
    if worker_id == "master" or fcntl is None:
        return build(tmp_path_factory.mktemp("built_fmus"))
    shared = tmp_path_factory.getbasetemp().parent  # this run's folder, common to the workers
    with open(shared / "built_fmus.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        out, done = shared / "built_fmus", shared / "built_fmus.done"
        if not done.exists():
            build(out)
            done.touch()
        return out


class QuickStudyCases:
    """The kept cases (``OUT/cases``) of the quick sweep studies, shared by the tests that run
    the same study at the same settings in one run.

    ``tests/test_studies.py`` runs ``run_study(NAME, quick=True, workers=0)`` and the
    docs/studies.md snippet runs ``pimodel study NAME --quick --workers 0``: the same cases
    (each case seeds its own generators), computed twice. Whichever runs first publishes its
    finished cases here; the other copies them into its own output folder before it runs, so
    the study loads them (the rerun path of ``pimodel.experiments.sweeps.run_cases``) and still
    aggregates, writes its tables and figures and is checked as before. Nothing waits: a test
    that finds no published cases computes them itself, as it did before. A folder is published
    whole (a temporary folder renamed), so a reader never sees half of it.
    """

    def __init__(self, root: Path):
        self.root = root

    def seed(self, name: str, cases: Path) -> bool:
        """Copy the published cases of study ``name`` into ``cases``; False when none yet."""
        import shutil

        src = self.root / name
        if not src.is_dir():
            return False
        shutil.copytree(src, cases, dirs_exist_ok=True)
        return True

    def publish(self, name: str, cases: Path) -> None:
        """Publish the finished cases in ``cases`` of study ``name`` (the first one stays)."""
        import shutil

        dest = self.root / name
        if dest.exists() or not cases.is_dir():
            return
        self.root.mkdir(parents=True, exist_ok=True)
        tmp = self.root / f".{name}.{os.getpid()}"
        shutil.copytree(cases, tmp)
        try:
            os.rename(tmp, dest)
        except OSError:  # another worker published first
            shutil.rmtree(tmp, ignore_errors=True)


@pytest.fixture(scope="session")
def quick_study_cases(tmp_path_factory, worker_id) -> QuickStudyCases:
    """The quick sweep studies' cases of this run, common to the pytest-xdist workers."""
    base = tmp_path_factory.getbasetemp()
    return QuickStudyCases((base if worker_id == "master" else base.parent) / "quick_study_cases")
