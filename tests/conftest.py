"""Shared test fixtures and helpers."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from hypothesis import settings

# No per-example deadline (a loaded 2-core machine makes timings noisy); in CI the examples are
# derandomised so that a run is reproducible.
settings.register_profile("default", deadline=None)
settings.register_profile("ci", deadline=None, derandomize=True)
settings.load_profile("ci" if os.environ.get("CI") else "default")

REPO = Path(__file__).resolve().parents[1]
SHARED_DATA = REPO.parent / "shared" / "data" / "real" / "smarthysteresis-piezo-1hz"
REAL_RECORD = SHARED_DATA / "piezo_1hz.csv"

# Seconds one test file takes in a whole run on two workers, roughly (only the order matters):
# the --durations logs of 25 Nov 2026 (a full run) and 26 Nov (half a run at load 30, scaled
# by its ratio to the first, about 6.5); the files added since are estimates (e).
# The files run longest first, each file's tests in their own order: quickstart.sh passes
# ``--dist loadfile --no-loadscope-reorder``, so pytest-xdist hands the files to the workers
# in this order (longest processing time first) instead of by their number of tests, which
# started the few long tests (the demo, the docs build, the 20 dB estimator test) last and
# left the other worker idle at the end. A file not listed counts as UNLISTED_SECONDS: list
# a new file that takes longer.
FILE_SECONDS: dict[str, float] = {
    "test_estimator_inputs.py": 300, "test_docs_snippets.py": 300, "test_fuzz_fmu.py": 236,
    "test_identify.py": 170, "test_studies.py": 140, "test_fmu_operators.py": 134,
    "test_diagnosed_block_fmu.py": 130, "test_estimator.py": 98, "test_wiener_stream.py": 90,
    "test_joint.py": 80, "test_sweep.py": 59, "test_docstrings.py": 56, "test_diagnosis.py": 53,
    "test_fuzz_cli.py": 52, "test_diagnosis_nominal_start.py": 40,  # e
    "test_fmu_importers.py": 40,  # e
    "test_inverse_native.py": 38, "test_augmented_feedforward.py": 36, "test_inverse_fmu.py": 31,
    "test_diagnosis_inputs.py": 30, "test_diagnosis_chunked.py": 30,  # e
    "test_diagnose_export.py": 26, "test_fmu.py": 26, "test_fuzz_api.py": 26,
    "test_diagnosis_alt.py": 24, "test_lti_stream.py": 22, "test_docs_build.py": 19,
    "test_fmu_spec.py": 20, "test_interrupts.py": 20, "test_diagnosis_summary.py": 20,  # e
    "test_diagnosed_model.py": 15, "test_fmu3.py": 15, "test_diagnosis_lti.py": 15,
    "test_demo.py": 14, "test_operator_extra_properties.py": 13, "test_diagnosis_wiener.py": 12,
    "test_diagnosis_drift.py": 11,
}
UNLISTED_SECONDS = 5.0


def pytest_collection_modifyitems(config, items) -> None:
    """Sort the tests by their file's FILE_SECONDS, longest first (a stable sort: each file
    stays in one piece and in its own order)."""
    items.sort(key=lambda item: -FILE_SECONDS.get(item.path.name, UNLISTED_SECONDS))


@pytest.fixture
def real_record_path() -> Path:
    """Path to the shared real piezo record; skips the test when ../shared is absent."""
    if not REAL_RECORD.exists():
        pytest.skip(f"shared real record not found at {REAL_RECORD} (needs ../shared beside "
                    "the repo)")
    return REAL_RECORD


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
