"""The FMU build's compile cache (pimodel.fmu.build_cache): a hit gives the same binary without
running the compiler; a change in a source, a header, a flag or a model's parameters misses for
exactly the objects that can see it; a truncated or corrupt entry is rebuilt; concurrent writers
leave only whole entries."""

from __future__ import annotations

import shutil
import subprocess
import threading
import zipfile
from pathlib import Path

import pytest

from pimodel.fmu import build as fmu_build
from pimodel.fmu import build_fmus
from pimodel.fmu import sources as fmu_sources
from pimodel.fmu.build_cache import ENV_VAR, cache_key, read_entry, write_entry
from pimodel.fmu.model_fmu import build_model_fmus
from pimodel.fmu.sources import CORE_SOURCES, HEADERS, source_dir
from pimodel.operators.creep import CreepOperator

UNIT = "PIHysteresis"
EVERY_C_FILE = {"model.c", *CORE_SOURCES}


def binary(fmu: Path) -> bytes:
    """The shared library inside an FMU."""
    with zipfile.ZipFile(fmu) as z:
        (name,) = [n for n in z.namelist() if n.startswith("binaries/")]
        return z.read(name)


@pytest.fixture(scope="module")
def seeded(tmp_path_factory) -> tuple[Path, bytes]:
    """A cache holding one cold build of PIHysteresis (FMI 2.0), and that build's binary."""
    folder = tmp_path_factory.mktemp("seeded_cache")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv(ENV_VAR, str(folder))
        (fmu,) = build_fmus(tmp_path_factory.mktemp("cold"), [UNIT])
    return folder, binary(fmu)


@pytest.fixture
def cache(seeded, tmp_path, monkeypatch) -> Path:
    """A copy of the seeded cache, this test's own."""
    folder = tmp_path / "cache"
    shutil.copytree(seeded[0], folder)
    monkeypatch.setenv(ENV_VAR, str(folder))
    return folder


class Compiler:
    """Records the compiler runs of a build (compiled C file, or "link"); with ``dry``, writes
    a stand-in output instead of compiling (for builds whose binary the test does not use)."""

    def __init__(self, dry: bool):
        self.dry, self.runs, self.lock = dry, [], threading.Lock()

    def __call__(self, cmd, cwd, what):
        with self.lock:
            self.runs.append(cmd[cmd.index("-c") + 1] if "-c" in cmd else "link")
        if self.dry:
            (Path(cwd) / cmd[cmd.index("-o") + 1]).write_bytes(b"stand-in")
        else:
            real_run(cmd, cwd, what)

    def compiled(self) -> set[str]:
        return {r for r in self.runs if r != "link"}


real_run = fmu_build._run


@pytest.fixture
def compiler(monkeypatch) -> Compiler:
    rec = Compiler(dry=False)
    monkeypatch.setattr(fmu_build, "_run", rec)
    return rec


@pytest.fixture
def dry_compiler(monkeypatch) -> Compiler:
    rec = Compiler(dry=True)
    monkeypatch.setattr(fmu_build, "_run", rec)
    return rec


@pytest.fixture
def sources_copy(tmp_path, monkeypatch) -> Path:
    """A copy of fmu/src that the build reads instead of the original."""
    src = tmp_path / "src"
    shutil.copytree(source_dir(), src)
    monkeypatch.setattr(fmu_sources, "source_dir", lambda: src)
    return src


def test_a_hit_gives_the_same_binary_without_compiling(seeded, cache, compiler, tmp_path):
    (fmu,) = build_fmus(tmp_path / "out", [UNIT])
    assert compiler.runs == []
    assert binary(fmu) == seeded[1]


def test_a_model_export_compiles_only_its_model_c(cache, compiler, tmp_path):
    """An exported model's config.h (its start values) differs from the unit's: model.c is
    compiled, the core's objects come from the cache; the same export again compiles nothing."""
    model = CreepOperator([0.05, 0.02], [0.1, 1.0], dt=1e-3)
    (first,) = build_model_fmus(model, tmp_path / "a")
    assert compiler.compiled() == {"model.c"} and compiler.runs.count("link") == 1
    compiler.runs.clear()
    (again,) = build_model_fmus(model, tmp_path / "b")
    assert compiler.runs == []
    assert binary(again) == binary(first)


def test_a_changed_flag_misses_every_object(cache, dry_compiler, monkeypatch, tmp_path):
    monkeypatch.setattr(fmu_build, "CFLAGS", [*fmu_build.CFLAGS, "-DPIM_CACHE_PROBE=1"])
    build_fmus(tmp_path / "out", [UNIT])
    assert dry_compiler.compiled() == EVERY_C_FILE
    assert dry_compiler.runs.count("link") == 1


def test_a_changed_core_source_recompiles_that_source_alone(cache, compiler, sources_copy,
                                                            tmp_path):
    with open(sources_copy / "core" / "pim_creep.c", "a") as f:
        f.write("\n/* a changed source: its object is compiled again */\n")
    build_fmus(tmp_path / "out", [UNIT])
    assert compiler.runs.count("pim_creep.c") == 1 and compiler.compiled() == {"pim_creep.c"}
    assert compiler.runs.count("link") == 1


@pytest.mark.parametrize(("header", "expected"), [
    ("fmi/pim_unit.h", {"model.c"}),             # the framework: only model.c includes it
    (f"units/{UNIT}/unit.h", {"model.c"}),       # the unit's hooks
    ("core/pim_core.h", EVERY_C_FILE),           # a core header: every C file may include it
])
def test_a_changed_header_misses_the_objects_that_can_include_it(
        cache, dry_compiler, sources_copy, tmp_path, header, expected):
    with open(sources_copy / header, "a") as f:
        f.write("\n/* changed */\n")
    build_fmus(tmp_path / "out", [UNIT])
    assert dry_compiler.compiled() == expected


def test_a_truncated_or_corrupt_entry_is_rebuilt(seeded, cache, compiler, tmp_path):
    """Truncate the binary's entry and flip a byte of one object's entry: that object is
    compiled again and the link rerun; the binary equals the first; every entry is whole again."""
    entries = sorted(p for p in cache.iterdir() if not p.name.startswith("."))
    so_entry = next(p for p in entries if read_entry(cache, p.name) == seeded[1])
    obj_entry = min((p for p in entries if p != so_entry), key=lambda p: p.stat().st_size)
    so_entry.write_bytes(so_entry.read_bytes()[:-100])
    data = bytearray(obj_entry.read_bytes())
    data[-1] ^= 0xFF
    obj_entry.write_bytes(bytes(data))
    assert read_entry(cache, so_entry.name) is None and read_entry(cache, obj_entry.name) is None
    (fmu,) = build_fmus(tmp_path / "out", [UNIT])
    assert len(compiler.compiled()) == 1 and compiler.runs.count("link") == 1
    assert binary(fmu) == seeded[1]
    assert all(read_entry(cache, p.name) is not None for p in entries)


def test_caching_off_writes_no_entry(dry_compiler, monkeypatch, tmp_path):
    monkeypatch.setenv(ENV_VAR, "off")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    build_fmus(tmp_path / "out", [UNIT])
    assert dry_compiler.compiled() == EVERY_C_FILE
    assert not (tmp_path / "xdg").exists() and not (tmp_path / "home").exists()


def test_an_unwritable_cache_only_costs_time(dry_compiler, monkeypatch, tmp_path):
    blocker = tmp_path / "not_a_folder"
    blocker.write_text("a file where the cache folder should be")
    monkeypatch.setenv(ENV_VAR, str(blocker / "cache"))
    (fmu,) = build_fmus(tmp_path / "out", [UNIT])
    assert binary(fmu) == b"stand-in" and dry_compiler.runs.count("link") == 1


def test_the_core_sources_include_only_the_core_headers():
    """A core object's key covers its source and the core headers (HEADERS); the compiler's
    own dependency list shows that nothing else of the FMU's sources can change it."""
    core = source_dir() / "core"
    for c in CORE_SOURCES:
        proc = subprocess.run([fmu_build.find_compiler(), "-MM", "-I", ".", c], cwd=core,
                              capture_output=True, text=True, check=True)
        deps = set(proc.stdout.replace("\\\n", " ").split(":", 1)[1].split())
        assert deps <= {c, *HEADERS}, (c, deps - {c, *HEADERS})


def test_keys_depend_on_every_part_and_file(tmp_path):
    a, b = tmp_path / "a.c", tmp_path / "b.c"
    a.write_text("int a;")
    b.write_text("int b;")
    key = cache_key("-O3", "cc 12", files=[a, b])
    assert key == cache_key("-O3", "cc 12", files=[a, b])
    assert key != cache_key("-O2", "cc 12", files=[a, b])
    assert key != cache_key("-O3", "cc 13", files=[a, b])
    assert key != cache_key("-O3", "cc 12", files=[b, a])
    assert cache_key("-O3", "x") != cache_key("-O3x")  # parts are delimited
    b.write_text("int b ;")
    assert key != cache_key("-O3", "cc 12", files=[a, b])


def test_concurrent_writers_and_readers_see_only_whole_entries(tmp_path):
    payloads = [bytes([i]) * 200_000 for i in range(4)]
    seen, errors = [], []

    def write(p):
        for _ in range(20):
            write_entry(tmp_path, "key", p)

    def read():
        for _ in range(200):
            got = read_entry(tmp_path, "key")
            if got is not None and got not in payloads:
                errors.append(len(got))
            seen.append(got is not None)

    threads = [threading.Thread(target=write, args=(p,)) for p in payloads]
    threads += [threading.Thread(target=read) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == [] and any(seen)
    assert read_entry(tmp_path, "key") in payloads
    assert [p.name for p in tmp_path.iterdir()] == ["key"]  # no temporary file left
