"""Shared test fixtures and helpers."""

from __future__ import annotations

from pathlib import Path

import pytest

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
