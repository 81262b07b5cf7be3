"""Build hook: compiles the shared C core (fmu/src/core/pim_*.c) into pimodel/_pim_core*.so.

The library is plain C (no Python C-API); pimodel._native loads it with ctypes.  The same
sources are compiled into the FMUs, so Python and FMI run one implementation.
"""

from glob import glob

from setuptools import Extension, setup

core = Extension(
    "pimodel._pim_core",
    sources=sorted(glob("fmu/src/core/pim_*.c")),
    include_dirs=["fmu/src/core"],
    extra_compile_args=["-std=c99", "-O3", "-Wall", "-Wextra", "-Werror", "-fvisibility=hidden"],
    libraries=["m"],
)

setup(ext_modules=[core])
