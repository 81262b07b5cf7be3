"""ctypes binding to the shared C core (``fmu/src/pim_*.c``), built at install time.

Only this module touches ctypes; the rest of the package calls the typed wrappers below.
"""

from __future__ import annotations

import ctypes
import importlib.machinery
from pathlib import Path

import numpy as np

_HERE = Path(__file__).resolve().parent


def _find_library() -> Path:
    for suffix in importlib.machinery.EXTENSION_SUFFIXES:
        candidate = _HERE / f"_pim_core{suffix}"
        if candidate.exists():
            return candidate
    raise ImportError(
        "pimodel's compiled core (_pim_core) is missing: install the package with "
        "'pip install -e .' (needs a C compiler) so that setup.py builds fmu/src/pim_*.c"
    )


lib = ctypes.CDLL(str(_find_library()))

# -- LIMITS: the C core's limits (fmu/src/core/pim_limits.h), read once -------------------------
# The only copy in Python: use LIMITS["PIM_MAX_PLAYS"] etc., never a retyped number.

lib.pim_limit_count.restype = ctypes.c_int
lib.pim_limit_count.argtypes = []
lib.pim_limit_name.restype = ctypes.c_char_p
lib.pim_limit_name.argtypes = [ctypes.c_int]
lib.pim_limit_value.restype = ctypes.c_double
lib.pim_limit_value.argtypes = [ctypes.c_int]
lib.pim_limit_is_integer.restype = ctypes.c_int
lib.pim_limit_is_integer.argtypes = [ctypes.c_int]

LIMITS: dict[str, int | float] = {
    lib.pim_limit_name(i).decode(): (int(lib.pim_limit_value(i)) if lib.pim_limit_is_integer(i)
                                     else lib.pim_limit_value(i))
    for i in range(lib.pim_limit_count())
}
"""Every limit and enumeration code of the C core and the FMU units (``fmu/src/core/pim_limits.h``)
by its C name,
e.g. ``LIMITS["PIM_MAX_PLAYS"]`` (the FMU arrays' size); integers as ``int``, tolerances as
``float``."""
#: envelope kinds of pim_generalized.h by name (the PIM_ENV_* codes)
ENVELOPE_KINDS: dict[str, int] = {k: LIMITS[f"PIM_ENV_{k.upper()}"]
                                  for k in ("poly2", "tanh", "poly2_inv", "tanh_inv")}
# -- end LIMITS --------------------------------------------------------------------------------

lib.pim_struct_size.restype = ctypes.c_size_t
lib.pim_struct_size.argtypes = [ctypes.c_char_p]


def _check_layout(mirror: type, c_name: str) -> None:
    """ImportError when a ctypes mirror and its C struct differ in size (a build mismatch)."""
    size = lib.pim_struct_size(c_name.encode())
    if ctypes.sizeof(mirror) != size:  # a build mismatch
        raise ImportError(f"pimodel: the ctypes layout of {c_name} ({ctypes.sizeof(mirror)} "
                          f"bytes) does not match the C core's ({size} bytes)")


c_size = ctypes.c_size_t
c_double_p = ctypes.POINTER(ctypes.c_double)

_F64 = np.ctypeslib.ndpointer(dtype=np.float64, flags="C_CONTIGUOUS")


class _NullableF64:
    """ctypes argtype accepting a float64 C-contiguous array or None (NULL)."""

    @classmethod
    def from_param(cls, obj):
        if obj is None:
            return None
        return _F64.from_param(obj)


F64 = _F64
F64_OR_NULL = _NullableF64

lib.pim_pi_step.restype = ctypes.c_double
lib.pim_pi_step.argtypes = [c_size, F64, F64, F64, ctypes.c_double]
lib.pim_pi_run.restype = None
lib.pim_pi_run.argtypes = [c_size, c_size, F64, F64, F64, F64, F64, F64_OR_NULL]
lib.pim_pi_run_rows.restype = None
lib.pim_pi_run_rows.argtypes = [c_size, c_size, F64, F64, F64, F64, F64, F64, c_size]
lib.pim_tdpi_run.restype = None
lib.pim_tdpi_run.argtypes = [c_size, c_size, F64, F64, F64, F64, F64, F64_OR_NULL]
lib.pim_pi_inverse.restype = ctypes.c_int
lib.pim_pi_inverse.argtypes = [c_size, F64, F64, F64_OR_NULL, F64, F64, F64_OR_NULL]


def pi_run(
    p: np.ndarray, r: np.ndarray, z: np.ndarray, v: np.ndarray, *, with_plays: bool = False
) -> tuple[np.ndarray, np.ndarray | None]:
    """Run the PI operator over ``v``; ``z`` (float64, length n) is updated in place."""
    N, n = v.shape[0], p.shape[0]
    y = np.empty(N)
    zhist = np.empty((N, n)) if with_plays else None
    lib.pim_pi_run(N, n, p, r, z, v, y, zhist)
    return y, zhist


def pi_run_rows(p: np.ndarray, r: np.ndarray, z: np.ndarray, v: np.ndarray,
                rows: np.ndarray) -> np.ndarray:
    """:func:`pi_run` with the play outputs written as rows, ``rows[i, k] = z_i[k]`` (float64,
    C-contiguous, shape (n, N), filled in place); ``z`` updated in place; returns ``y``. The
    same values as :func:`pi_run`'s."""
    N, n = v.shape[0], p.shape[0]
    if rows.shape != (n, N):
        raise ValueError(f"rows: expected shape ({n}, {N}), got {rows.shape}")
    y = np.empty(N)
    lib.pim_pi_run_rows(N, n, p, r, z, v, y, rows, N)
    return y


def tdpi_run(
    p: np.ndarray, R: np.ndarray, z: np.ndarray, v: np.ndarray, *, with_plays: bool = False
) -> tuple[np.ndarray, np.ndarray | None]:
    """Time-dependent PI operator, radii ``R[k, i]`` per sample; ``z`` updated in place."""
    N, n = v.shape[0], p.shape[0]
    y = np.empty(N)
    zhist = np.empty((N, n)) if with_plays else None
    lib.pim_tdpi_run(N, n, p, R, z, v, y, zhist)
    return y, zhist


def pi_step(p: np.ndarray, r: np.ndarray, z: np.ndarray, v: float) -> float:
    """One step of the PI operator; ``z`` updated in place."""
    return lib.pim_pi_step(p.shape[0], p, r, z, float(v))


def pi_inverse(
    p: np.ndarray, r: np.ndarray, z: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None] | None:
    """Inverse weights, radii and consistent state; None when not invertible."""
    n = p.shape[0]
    pinv, rinv = np.empty(n), np.empty(n)
    zinv = np.empty(n) if z is not None else None
    if lib.pim_pi_inverse(n, p, r, z, pinv, rinv, zinv) != 0:
        return None
    return pinv, rinv, zinv


# -- raw PI step for python-control blocks (pointers cached by the caller) -----------------------

raw_pi_step = lib["pim_pi_step"]  # a second handle: raw pointers, no ndpointer argument checks
raw_pi_step.restype = ctypes.c_double
raw_pi_step.argtypes = [c_size, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_double]

lib.pim_adaptive_inverse_step.restype = ctypes.c_double
lib.pim_adaptive_inverse_step.argtypes = [c_size, F64, F64, F64, ctypes.c_double]


def address(a: np.ndarray) -> int:
    """The data address of a C-contiguous float64 array, for :data:`raw_pi_step` (and the
    joint estimator's calls, :func:`_f64_address`)."""
    return a.__array_interface__["data"][0]  # the value of a.ctypes.data, without its object


# -- radius estimator (fmu/src/pim_estimator.h) -------------------------------------------------

_D = ctypes.POINTER(ctypes.c_double)
lib.pim_est_sizeof.restype = c_size
lib.pim_est_init.restype = ctypes.c_char_p
lib.pim_est_init.argtypes = [ctypes.c_void_p, c_size, F64, F64, F64, ctypes.c_double,
                             ctypes.c_double, ctypes.c_double, ctypes.c_double, ctypes.c_double,
                             ctypes.c_double, ctypes.c_int]
lib.pim_est_step.restype = ctypes.c_int
lib.pim_est_step.argtypes = [ctypes.c_void_p, ctypes.c_double, ctypes.c_double, F64_OR_NULL, _D,
                             _D, _D]
lib.pim_est_run.restype = ctypes.c_long
lib.pim_est_run.argtypes = [ctypes.c_void_p, c_size, F64, F64, F64_OR_NULL, F64, F64, F64,
                            F64_OR_NULL]
lib.pim_est_get_state.restype = None
lib.pim_est_get_state.argtypes = [ctypes.c_void_p, F64]
lib.pim_est_set_state.restype = ctypes.c_char_p
lib.pim_est_set_state.argtypes = [ctypes.c_void_p, F64]
lib.pim_est_set_slope_check.restype = ctypes.c_char_p
lib.pim_est_set_slope_check.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_double]
lib.pim_est_set_law.restype = ctypes.c_char_p
lib.pim_est_set_law.argtypes = [ctypes.c_void_p, ctypes.c_int]
lib.pim_project_ordered.restype = None
lib.pim_project_ordered.argtypes = [c_size, F64, F64, ctypes.c_int]


def estimator_buffer() -> ctypes.Array:
    """Zeroed storage for one ``pim_estimator`` (``pim_est_sizeof()`` bytes)."""
    return ctypes.create_string_buffer(lib.pim_est_sizeof())


def estimator_step(buf: ctypes.Array, v: float, y: float) -> tuple[int, float, float, float]:
    """One estimator sample: ``(rc, y_hat, e, e_dot)`` (``pim_est_step``)."""
    yh, e, ed = ctypes.c_double(), ctypes.c_double(), ctypes.c_double()
    rc = lib.pim_est_step(buf, v, y, None, ctypes.byref(yh), ctypes.byref(e), ctypes.byref(ed))
    return rc, yh.value, e.value, ed.value


# -- compiled closed loops (fmu/src/pim_loops.h) ------------------------------------------------

LOOP_MAX_PLAYS, LOOP_MAX_DYN = LIMITS["PIM_MAX_PLAYS"], LIMITS["PIM_MAX_DYN"]
_EST_WORDS = lib.pim_est_sizeof() // 8
_D64 = ctypes.c_double * LOOP_MAX_PLAYS


class Loop(ctypes.Structure):
    """``pim_loop``: plant, feedforward, estimator copy and PID of a compiled loop."""

    _fields_ = [
        ("n", c_size), ("p", _D64), ("r", _D64), ("z", _D64),
        ("nx", c_size), ("A", ctypes.c_double * (LOOP_MAX_DYN * LOOP_MAX_DYN)),
        ("B", ctypes.c_double * LOOP_MAX_DYN), ("C", ctypes.c_double * LOOP_MAX_DYN),
        ("D", ctypes.c_double), ("xd", ctypes.c_double * LOOP_MAX_DYN),
        ("ff_mode", ctypes.c_int), ("ff_gain", ctypes.c_double),
        ("ni", c_size), ("pinv", _D64), ("rinv", _D64), ("zinv", _D64),
        ("nm", c_size), ("pm", _D64), ("zm", _D64),
        ("est", ctypes.c_double * _EST_WORDS),
        ("pid_on", ctypes.c_int), ("kp", ctypes.c_double), ("ki", ctypes.c_double),
        ("kd", ctypes.c_double), ("tf", ctypes.c_double), ("dt", ctypes.c_double),
        ("integ", ctypes.c_double), ("dfilt", ctypes.c_double), ("e_prev", ctypes.c_double),
    ]


lib.pim_loop_sizeof.restype = c_size
if ctypes.sizeof(Loop) != lib.pim_loop_sizeof():  # pragma: no cover - build mismatch guard
    raise ImportError("pimodel: the ctypes layout of pim_loop does not match the C core")
lib.pim_loop_run.restype = ctypes.c_int
lib.pim_loop_run.argtypes = [ctypes.POINTER(Loop), c_size, F64, F64, F64_OR_NULL, F64_OR_NULL,
                             F64_OR_NULL]


def loop_take_estimator(L: Loop, buf: ctypes.Array) -> None:
    """Copy an estimator's state (:func:`estimator_buffer`) into the loop's ``est`` field."""
    ctypes.memmove(ctypes.addressof(L) + Loop.est.offset, ctypes.addressof(buf),
                   ctypes.sizeof(L.est))


def loop_run(L: Loop, r: np.ndarray, y: np.ndarray, v, e, R) -> int:
    """Run the loop over ``r`` (``pim_loop_run``); 0 on success."""
    return lib.pim_loop_run(ctypes.byref(L), r.size, r, y, v, e, R)


# -- reversal scanner (fmu/src/pim_reversals.h) -------------------------------------------------

_I64 = np.ctypeslib.ndpointer(dtype=np.int64, flags="C_CONTIGUOUS")
lib.pim_rev_scan_sizeof.restype = c_size
lib.pim_rev_scan_init.restype = None
lib.pim_rev_scan_init.argtypes = [ctypes.c_void_p]
lib.pim_rev_scan_run.restype = c_size
lib.pim_rev_scan_run.argtypes = [ctypes.c_void_p, c_size, F64, ctypes.c_double, _I64, _I64]


def reversal_scanner() -> ctypes.Array:
    """A fresh ``pim_rev_scan`` state (initialised)."""
    buf = ctypes.create_string_buffer(lib.pim_rev_scan_sizeof())
    lib.pim_rev_scan_init(buf)
    return buf


# -- joint estimator's branch statistics (fmu/src/core/pim_joint.h) -------------------------

lib.pim_joint_select.restype = c_size
lib.pim_joint_select.argtypes = [c_size, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_double,
                                 ctypes.c_double, ctypes.c_double, ctypes.c_void_p,
                                 ctypes.c_void_p, ctypes.POINTER(ctypes.c_longlong)]
lib.pim_joint_hinges.restype = None
lib.pim_joint_hinges.argtypes = [c_size, ctypes.c_void_p, c_size, ctypes.c_void_p,
                                 ctypes.c_void_p]
lib.pim_joint_add.restype = ctypes.c_double
lib.pim_joint_add.argtypes = [c_size, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p,
                              ctypes.c_double, c_size, ctypes.c_double, ctypes.c_double,
                              ctypes.c_void_p, ctypes.c_void_p]


def _f64_address(a: np.ndarray, name: str) -> int:
    """The data address of a float64 C-contiguous array (the joint estimator calls these
    functions once per branch, where numpy's ``ndpointer`` checks cost as much as the work)."""
    if a.dtype != np.float64 or not a.flags.c_contiguous:
        raise TypeError(f"{name}: expected a C-contiguous float64 array")
    return address(a)


def joint_select(v: np.ndarray, y: np.ndarray, s: float, keep_limit: float,
                 travel_range: float) -> tuple[np.ndarray, np.ndarray, int]:
    """The samples of a finished branch the joint estimator uses (``pim_joint_select``):
    ``v`` the branch's inputs from its reversal extreme, ``y`` their outputs (float64,
    C-contiguous, equal lengths). Returns the travels ``x``, the signed outputs ``Y`` and the
    count of samples beyond ``travel_range``."""
    N = v.shape[0]
    if y.shape != (N,) or N < 1:
        raise ValueError(f"v and y: expected one length >= 1, got {v.shape} and {y.shape}")
    x, Y, outside = np.empty(N), np.empty(N), ctypes.c_longlong(0)
    m = lib.pim_joint_select(N, _f64_address(v, "v"), _f64_address(y, "y"), s, keep_limit,
                             travel_range, _f64_address(x, "x"), _f64_address(Y, "Y"),
                             ctypes.byref(outside))
    return x[:m], Y[:m], outside.value


def joint_hinges(x: np.ndarray, r: np.ndarray) -> np.ndarray:
    """``max(0, x[k] - 2 r[j])`` as an (m, n) array (``pim_joint_hinges``): the values of
    ``np.maximum(0.0, x[:, None] - 2.0 * r[None, :])`` in one pass."""
    m, n = x.shape[0], r.shape[0]
    H = np.empty((m, n))
    lib.pim_joint_hinges(m, _f64_address(x, "x"), n, _f64_address(r, "r"), _f64_address(H, "H"))
    return H


def joint_add(x: np.ndarray, Y: np.ndarray, e: np.ndarray, c: float, stats: np.ndarray,
              travel_range: float, forgetting: float) -> float:
    """Selected branch samples ``(x, Y)`` centred by ``c`` (the mean of their errors ``e``
    about the estimate in force) and added to ``stats`` (float64, shape (3, bins), updated in
    place) (``pim_joint_add``); returns ``sum (e - c)^2``."""
    m, bins = x.shape[0], stats.shape[1]
    if Y.shape != (m,) or e.shape != (m,) or stats.shape != (3, bins) or m < 1:
        raise ValueError("joint_add: expected x, Y, e of one length >= 1 and stats of shape "
                         "(3, bins)")
    scratch = np.empty(3 * bins)
    return lib.pim_joint_add(m, _f64_address(x, "x"), _f64_address(Y, "Y"),
                             _f64_address(e, "e"), c, bins, bins / travel_range, forgetting,
                             _f64_address(stats, "stats"), _f64_address(scratch, "scratch"))


# -- generalized, rate-dependent and creep operators (fmu/src/pim_generalized.h,
#    pim_rate_dependent.h, pim_creep.h) --------------------------------------------------------

c_int = ctypes.c_int
c_double = ctypes.c_double

lib.pim_envelope.restype = c_double
lib.pim_envelope.argtypes = [c_int, F64, c_double]
lib.pim_envelope_check.restype = ctypes.c_char_p
lib.pim_envelope_check.argtypes = [c_int, F64]
lib.pim_gpi_run.restype = c_size
lib.pim_gpi_run.argtypes = [c_size, c_size, F64, F64, F64, c_int, F64, c_int, F64, F64, F64]
lib.pim_play_solve.restype = c_double
lib.pim_play_solve.argtypes = [c_size, F64, F64, F64, c_double]
lib.pim_rdpi_run.restype = None
lib.pim_rdpi_run.argtypes = [c_size, c_size, F64, F64, c_double, c_double, c_double, F64, F64,
                             F64, F64]
lib.pim_rdpi_sat_run.restype = None
lib.pim_rdpi_sat_run.argtypes = [c_size, c_size, F64, F64, c_double, c_double, c_double,
                                 c_double, F64, F64, F64, F64]
lib.pim_rdpi_sat_plays.restype = None
lib.pim_rdpi_sat_plays.argtypes = [c_size, c_size, F64, c_double, c_double, c_double, c_double,
                                   F64, F64, F64, F64]
lib.pim_rdpi_sat_plays_strided.restype = None
lib.pim_rdpi_sat_plays_strided.argtypes = [c_size, c_size, F64, c_double, c_double, c_double,
                                           c_double, F64, F64, F64, F64, c_size, c_size]
lib.pim_rdpi_inverse_run.restype = c_int
lib.pim_rdpi_inverse_run.argtypes = [c_size, c_size, F64, F64, c_double, c_double, c_double, F64,
                                     F64, F64, F64]
lib.pim_creep_run.restype = None
lib.pim_creep_run.argtypes = [c_size, c_size, F64, F64, F64, F64, F64]
lib.pim_creep_inverse_run.restype = None
lib.pim_creep_inverse_run.argtypes = [c_size, c_size, F64, F64, F64, F64, F64]


def envelope_check(kind: int, c: np.ndarray) -> str | None:
    """Message naming the bad coefficient of an envelope, or None when it is valid."""
    msg = lib.pim_envelope_check(kind, c)
    return None if msg is None else msg.decode()


def gpi_run(p: np.ndarray, r: np.ndarray, z: np.ndarray, kind_in: int, c_in: np.ndarray,
            kind_out: int, c_out: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, int]:
    """Generalized PI run; ``z`` updated in place. Returns ``(y, bad)``, ``bad`` = k + 1 of the
    first sample where an envelope is undefined, else 0."""
    y = np.empty(v.shape[0])
    bad = lib.pim_gpi_run(v.shape[0], p.shape[0], p, r, z, kind_in, c_in, kind_out, c_out, v, y)
    return y, int(bad)


def rdpi_run(p: np.ndarray, alpha: np.ndarray, beta: float, lam: float, Ts: float,
             z: np.ndarray, hist: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rate-dependent PI run; ``z`` (n) and ``hist`` (v[k-1], rate[k]) updated in place."""
    y = np.empty(v.shape[0])
    lib.pim_rdpi_run(v.shape[0], p.shape[0], p, alpha, beta, lam, Ts, z, hist, v, y)
    return y


def rdpi_sat_run(p: np.ndarray, alpha: np.ndarray, beta: float, sat: float, lam: float,
                 Ts: float, z: np.ndarray, hist: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rate-dependent PI run with a saturating radius growth (``sat`` <= 0: none); ``z`` (n)
    and ``hist`` (v[k-1], rate[k]) updated in place."""
    y = np.empty(v.shape[0])
    lib.pim_rdpi_sat_run(v.shape[0], p.shape[0], p, alpha, beta, sat, lam, Ts, z, hist, v, y)
    return y


def rdpi_sat_plays(alpha: np.ndarray, beta: float, sat: float, lam: float, Ts: float,
                   z: np.ndarray, hist: np.ndarray, v: np.ndarray, *,
                   rows: bool = False) -> np.ndarray:
    """The play outputs ``z_i[k]`` of :func:`rdpi_sat_run` (shape (N, n); ``rows``: (n, N),
    written so, the same values), every play on the one rate; ``z`` (n) and ``hist`` (v[k-1],
    rate[k]) updated in place."""
    N, n = v.shape[0], alpha.shape[0]
    out = np.empty((n, N) if rows else (N, n))
    lib.pim_rdpi_sat_plays_strided(N, n, alpha, beta, sat, lam, Ts, z, hist, v, out,
                                   *((1, N) if rows else (n, 1)))
    return out


def rdpi_inverse_run(p: np.ndarray, alpha: np.ndarray, beta: float, lam: float, Ts: float,
                     z: np.ndarray, hist: np.ndarray, yd: np.ndarray) -> np.ndarray:
    """Exact inverse of the rate-dependent PI; the forward state ``z``, ``hist`` advances."""
    v = np.empty(yd.shape[0])
    if lib.pim_rdpi_inverse_run(yd.shape[0], p.shape[0], p, alpha, beta, lam, Ts, z, hist, yd,
                                v):
        raise ValueError(f"rate-dependent inverse: at most 64 plays, got {p.shape[0]}")
    return v


def creep_run(a: np.ndarray, c: np.ndarray, x: np.ndarray, u: np.ndarray, *,
              inverse: bool = False) -> np.ndarray:
    """Creep operator (or, with ``inverse=True``, its inverse) over ``u``; ``x`` updated."""
    out = np.empty(u.shape[0])
    fn = lib.pim_creep_inverse_run if inverse else lib.pim_creep_run
    fn(u.shape[0], a.shape[0], a, c, x, u, out)
    return out


class AsymParams(ctypes.Structure):
    """``pim_asym`` (fmu/src/pim_asymmetric.h): direct weight, envelopes and shape function."""

    _fields_ = [("p0", c_double), ("al", c_double), ("dl", c_double), ("ar", c_double),
                ("dr", c_double), ("kind", c_int), ("c", c_double * 4), ("kind_inv", c_int)]


_check_layout(AsymParams, "pim_asym")
lib.pim_asym_run.restype = c_size
lib.pim_asym_run.argtypes = [ctypes.POINTER(AsymParams), c_size, c_size, F64, F64, F64, F64, F64]
lib.pim_asym_inverse_run.restype = c_size
lib.pim_asym_inverse_run.argtypes = [ctypes.POINTER(AsymParams), c_size, c_size, F64, F64, F64,
                                     F64, F64]


def asym_run(a: AsymParams, p: np.ndarray, r: np.ndarray, z: np.ndarray, x: np.ndarray, *,
             inverse: bool = False) -> tuple[np.ndarray, int]:
    """Asymmetric generalized PI (or its inverse) over ``x``; ``z`` updated in place.
    Returns ``(out, bad)``, ``bad`` = k + 1 of the first failing sample, else 0."""
    out = np.empty(x.shape[0])
    fn = lib.pim_asym_inverse_run if inverse else lib.pim_asym_run
    bad = fn(ctypes.byref(a), x.shape[0], p.shape[0], p, r, z, x, out)
    return out, int(bad)


# -- the diagnosed model (fmu/src/pim_diagnosed.h) ---------------------------------------------

_DP = ctypes.POINTER(ctypes.c_double)


class DiagParams(ctypes.Structure):
    """``pim_diag`` (fmu/src/pim_diagnosed.h): the model a diagnosis chose, for the C step."""

    _fields_ = [("n", c_size), ("w", _DP), ("r", _DP), ("w0", _DP), ("c", c_double),
                ("c0", c_double), ("m", c_size), ("lag_a", _DP), ("lag_g", _DP),
                ("asym", c_int), ("q", c_double), ("c3", c_double), ("center", c_double),
                ("half", c_double), ("rate_w", _DP), ("dt", c_double),
                ("rate_scale", c_double), ("input_range", c_double), ("rate_family", c_int),
                ("rate_tau", c_double), ("rate_saturation", c_double),
                ("rate_growth", c_double), ("order", c_size),
                ("b", _DP), ("a", _DP), ("delay", c_double), ("drift_clock", c_int),
                ("drift", c_double), ("ne", c_size), ("el_b", _DP), ("el_a", _DP),
                ("el_g", _DP), ("nw", c_size), ("wf_b", _DP), ("wf_a", _DP),
                ("plays_start", c_int), ("settle", c_double), ("settle_tau", c_double),
                ("settle_t0", c_double), ("lag_start", _DP), ("lag_record", c_int)]


_check_layout(DiagParams, "pim_diag")
lib.pim_diag_state_size.restype = c_size
lib.pim_diag_state_size.argtypes = [ctypes.POINTER(DiagParams)]
lib.pim_diag_check.restype = ctypes.c_char_p
lib.pim_diag_check.argtypes = [ctypes.POINTER(DiagParams)]
lib.pim_diag_initial_state.restype = None
lib.pim_diag_initial_state.argtypes = [ctypes.POINTER(DiagParams), F64, c_double]
lib.pim_diag_step.restype = c_double
lib.pim_diag_step.argtypes = [ctypes.POINTER(DiagParams), F64, c_double, c_double]
lib.pim_diag_run.restype = None
lib.pim_diag_run.argtypes = [ctypes.POINTER(DiagParams), F64, c_size, F64, F64_OR_NULL, F64]


def diag_pointer(a: np.ndarray | None):
    """A ``double *`` into ``a`` (float64, C-contiguous, kept alive by the caller), or NULL."""
    return None if a is None else a.ctypes.data_as(_DP)


def diag_state_size(d: DiagParams) -> int:
    """Length of the model's flat state."""
    return int(lib.pim_diag_state_size(ctypes.byref(d)))


def diag_initial_state(d: DiagParams, z0: float = 0.0) -> np.ndarray:
    """The state before the first sample: zeros, the plays (and a prefilter's plays) at z0."""
    x = np.empty(diag_state_size(d))
    lib.pim_diag_initial_state(ctypes.byref(d), x, float(z0))
    return x


def diag_check(d: DiagParams) -> str | None:
    """Message naming the first bad parameter, or None."""
    msg = lib.pim_diag_check(ctypes.byref(d))
    return None if msg is None else msg.decode()


def diag_step(d: DiagParams, x: np.ndarray, v: float, t: float) -> float:
    """One sample ``y[k]``; the state ``x`` advances in place."""
    return lib.pim_diag_step(ctypes.byref(d), x, float(v), float(t))


def diag_run(d: DiagParams, x: np.ndarray, v: np.ndarray, t: np.ndarray | None) -> np.ndarray:
    """``y[k]`` for ``v[0..N-1]`` at times ``t`` (None: ``k dt``); ``x`` advances in place."""
    y = np.empty(v.shape[0])
    lib.pim_diag_run(ctypes.byref(d), x, v.shape[0], v, t, y)
    return y


# -- the diagnosed model's feedforward (fmu/src/pim_diag_inverse.h) ---------------------------


class InverseParams(ctypes.Structure):
    """``pim_dinv`` (fmu/src/pim_diag_inverse.h): a diagnosed model's causal feedforward."""

    _fields_ = [("n", c_size), ("w", _DP), ("r", _DP), ("w0", _DP), ("c", c_double),
                ("c0", c_double), ("m", c_size), ("lag_a", _DP), ("lag_g", _DP),
                ("asym", c_int), ("q", c_double), ("c3", c_double), ("center", c_double),
                ("half", c_double), ("rate_w", _DP), ("dt", c_double),
                ("rate_scale", c_double), ("input_range", c_double), ("rate_family", c_int),
                ("rate_tau", c_double), ("rate_saturation", c_double),
                ("rate_growth", c_double), ("reference_range", c_double), ("ns", c_size),
                ("sos", _DP), ("latency", c_size), ("frac", c_double), ("npost", c_size),
                ("post", _DP), ("lag_start", _DP), ("lag_record", c_int)]


_check_layout(InverseParams, "pim_dinv")
_IP = ctypes.POINTER(InverseParams)
lib.pim_dinv_state_size.restype = c_size
lib.pim_dinv_state_size.argtypes = [_IP]
lib.pim_dinv_check.restype = ctypes.c_char_p
lib.pim_dinv_check.argtypes = [_IP]
lib.pim_dinv_initial_state.restype = None
lib.pim_dinv_initial_state.argtypes = [_IP, F64, F64_OR_NULL]
lib.pim_dinv_step.restype = c_double
lib.pim_dinv_step.argtypes = [_IP, F64, c_double]
lib.pim_dinv_run.restype = None
lib.pim_dinv_run.argtypes = [_IP, F64, c_size, F64, F64]


def inverse_state_size(d: InverseParams) -> int:
    """Length of the feedforward's flat state."""
    return int(lib.pim_dinv_state_size(ctypes.byref(d)))


def inverse_check(d: InverseParams) -> str | None:
    """Message naming the first bad parameter, or None."""
    msg = lib.pim_dinv_check(ctypes.byref(d))
    return None if msg is None else msg.decode()


def inverse_initial_state(d: InverseParams, z0: np.ndarray | None = None) -> np.ndarray:
    """The state before the first sample: zeros, the plays at ``z0`` (None: 0)."""
    x = np.empty(inverse_state_size(d))
    lib.pim_dinv_initial_state(ctypes.byref(d), x, z0)
    return x


def inverse_step(d: InverseParams, x: np.ndarray, y_d: float) -> float:
    """One sample ``v[k]``; the state ``x`` advances in place."""
    return lib.pim_dinv_step(ctypes.byref(d), x, float(y_d))


def inverse_run(d: InverseParams, x: np.ndarray, y_d: np.ndarray) -> np.ndarray:
    """``v[k]`` for ``y_d[0..N-1]``; ``x`` advances in place."""
    v = np.empty(y_d.shape[0])
    lib.pim_dinv_run(ctypes.byref(d), x, y_d.shape[0], y_d, v)
    return v


# -- health of a radius estimate (fmu/src/pim_est_health.h) ------------------------------------

HEALTH_EXCITATION, HEALTH_MERGED, HEALTH_PINNED, HEALTH_MOVING, HEALTH_FIT = 1, 2, 4, 8, 16
HEALTH_MAX_PLAYS = LIMITS["PIM_MAX_PLAYS"]

lib.pim_health_sizeof.restype = c_size
lib.pim_health_init.restype = ctypes.c_char_p
lib.pim_health_init.argtypes = [ctypes.c_void_p, c_size, c_int]
lib.pim_health_add.restype = None
lib.pim_health_add.argtypes = [ctypes.c_void_p, c_size, F64_OR_NULL, F64, F64_OR_NULL,
                               F64_OR_NULL]
lib.pim_health_eval.restype = c_int
lib.pim_health_eval.argtypes = [ctypes.c_void_p, F64, c_int, ctypes.c_long, c_double_p,
                                c_double_p, F64_OR_NULL, np.ctypeslib.ndpointer(dtype=np.intc),
                                np.ctypeslib.ndpointer(dtype=np.intc)]


def health_checks(weights: np.ndarray, history: np.ndarray, *, linear_play: bool,
                  v: np.ndarray | None = None, reversals: int = 0, y: np.ndarray | None = None,
                  error: np.ndarray | None = None) -> dict:
    """The C health checks (``pim_health_eval``) on ``history`` (N x n rows ``rhat[k]``, 1 <= n
    <= 64): ``flags`` (bit mask), ``drift``, ``input_range`` (0 without ``v``), ``fit`` (RMS of
    ``error`` over the last quarter and its bound, zeros without ``y`` and ``error``),
    ``merged`` (n - 1 booleans) and ``pinned`` (n booleans)."""
    hist = np.ascontiguousarray(history, dtype=np.float64)
    n = hist.shape[1]
    buf = ctypes.create_string_buffer(lib.pim_health_sizeof())
    with_fit = y is not None and error is not None
    msg = lib.pim_health_init(buf, n, int(with_fit))
    if msg:
        raise ValueError(f"history: {msg.decode()} (got {n} columns)")
    x = None if v is None else np.ascontiguousarray(v, dtype=np.float64)
    ys, es = ((np.ascontiguousarray(y, dtype=np.float64),
               np.ascontiguousarray(error, dtype=np.float64)) if with_fit else (None, None))
    lib.pim_health_add(buf, hist.shape[0], x, hist, ys, es)
    drift, rng, fit = c_double(), c_double(), np.zeros(2)
    merged, pinned = np.zeros(max(n - 1, 1), np.intc), np.zeros(n, np.intc)
    p = np.ascontiguousarray(weights, dtype=np.float64)
    flags = lib.pim_health_eval(buf, p, int(linear_play), int(reversals), ctypes.byref(drift),
                                ctypes.byref(rng), fit, merged, pinned)
    return {"flags": int(flags), "drift": drift.value, "input_range": rng.value, "fit": fit,
            "merged": merged[: n - 1].astype(bool), "pinned": pinned.astype(bool)}


lib.pim_biquad_rows.restype = None
lib.pim_biquad_rows.argtypes = [c_size, c_size, F64, F64, F64, F64]


def biquad_rows(b: np.ndarray, a: np.ndarray, x: np.ndarray) -> np.ndarray:
    """A filter of order <= 2 (``b``, ``a`` with ``a[0] = 1``) on each row of ``x``, each row at
    rest around its first sample (``fmu/src/pim_filter.h``; equals
    ``scipy.signal.lfilter(b, a, x, zi=lfilter_zi(b, a)[None, :] * x[:, :1])``).

    Parameters
    ----------
    b, a : numpy.ndarray
        Numerator and denominator in powers of ``z^-1``, at most 3 coefficients each.
    x : numpy.ndarray
        Signals as rows, shape (m, N) (1-D: one signal).

    Returns
    -------
    numpy.ndarray
        The filtered signals, shape of ``x``.
    """
    bb, aa = np.zeros(3), np.zeros(3)
    bb[:len(b)], aa[:len(a)] = b, a
    xc = np.ascontiguousarray(x, dtype=float)
    out = np.empty_like(xc)
    rows = xc.reshape(-1, xc.shape[-1]) if xc.ndim else xc
    lib.pim_biquad_rows(rows.shape[0], rows.shape[1], bb, aa, rows, out.reshape(rows.shape))
    return out


lib.pim_biquad_rows_carry.restype = None
lib.pim_biquad_rows_carry.argtypes = [c_size, c_size, F64, F64, F64, F64, F64, ctypes.c_int]


def biquad_rows_carry(b: np.ndarray, a: np.ndarray, x: np.ndarray,
                      state: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """:func:`biquad_rows` on a chunk of each row, the filter's state carried
    (``fmu/src/pim_filter.h``): the chunks of a row filtered in turn, each with the state the
    previous one returned, give the bits of :func:`biquad_rows` on the whole row.

    Parameters
    ----------
    b, a : numpy.ndarray
        Numerator and denominator in powers of ``z^-1``, at most 3 coefficients each.
    x : numpy.ndarray
        The chunk, signals as rows, shape (m, L) (1-D: one signal).
    state : numpy.ndarray or None
        The states ``s0[k-1], s1[k-1]`` before the chunk, shape (m, 2), as returned for the
        previous chunk; None: the rows' first chunk (at rest around its first sample).

    Returns
    -------
    y, state : numpy.ndarray
        The filtered chunk (shape of ``x``) and the states after its last sample, (m, 2).
    """
    bb, aa = np.zeros(3), np.zeros(3)
    bb[:len(b)], aa[:len(a)] = b, a
    xc = np.ascontiguousarray(x, dtype=float)
    out = np.empty_like(xc)
    rows = xc.reshape(-1, xc.shape[-1])
    s = np.zeros((rows.shape[0], 2)) if state is None else np.array(state, float, order="C")
    lib.pim_biquad_rows_carry(rows.shape[0], rows.shape[1], bb, aa, rows,
                              out.reshape(rows.shape), s, int(state is None))
    return out, s
