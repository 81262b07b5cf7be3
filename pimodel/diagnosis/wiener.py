"""The ``dynamics`` candidate with its linear part *before* the hysteresis (a Wiener model): a
filter ``F`` between the input ``v`` and the plays, such as the bandwidth of the amplifier that
drives the stage.

Form: ``x = F[v]`` (every element of unit static gain, zero-order-hold discretised, started at
rest around ``v[0]``), then the hysteresis of ``x``: the play outputs ``Gamma_{r_i}[x]`` (plays at
rest at 0) weighted jointly with the other effects' columns, as in :mod:`.effects`; the other
effects' columns are still built from the nominal hysteresis ``h0`` of ``v``. ``F`` is one
element (:func:`pimodel.diagnosis.lti.element_coefficients`):

- ``("lowpass", tau)``: a first-order low-pass ``1 / (tau s + 1)`` [s] (1 parameter);
- ``("lowpass_direct", tau)``: the same low-pass sampled at the end of each hold,
  ``x[k] = a x[k-1] + (1 - a) v[k]`` (``a = exp(-dt / tau)``; 1 parameter): the ZOH form
  advanced one sample, as when the sensor samples the stage just before the next update;
- ``("mode", fn, zeta)``: ``w^2 / (s^2 + 2 zeta w s + w^2)`` [Hz, -]; a damping of 1 or more
  is a second-order low-pass with real poles (2 parameters).

``x[k]`` depends on ``v[0..k-1]`` for ``"lowpass"`` and ``"mode"`` (strictly proper under the
hold), on ``v[0..k]`` for ``"lowpass_direct"``; the output ``y[k]`` likewise. Because the play
outputs of ``F[v]`` are no linear function of the filter's parameters, every point of the
search runs the plays again (:class:`WienerBasis`).

Selection (:func:`search_filter`): every kind on a coarse grid (the low-passes' corners
``LOWPASS_SLOW_HZ`` from ``LOWPASS_MIN_HZ``, then ``LOWPASS_HZ`` points from ``MIN_HZ``;
``MODE_HZ`` x ``MODE_DAMPING``), the best of each refined by Nelder-Mead on the train residual
(:mod:`.effects` scores the low-passes with every play column: the leading columns of its mode
searches, principal directions of the unfiltered plays, misfit the hysteresis of a filtered
input by some 200 times the noise, and ramps and holds behind a 40-150 Hz amplifier then read
``delay``; the mode with the leading columns, then with every column), and the kind with the
lowest train BIC ``N ln(RSS / N) + k ln N`` kept; the
candidate then keeps this Wiener variant when its train BIC is lower than that of the
Hammerstein variant (:mod:`.lti`, refitted with every column), with ``k`` counted the same way
(2 for the base mode plus 3 per further mode there; 1 or 2 here).
The position is decided on the ``dynamics`` candidate alone; beside other effects, where it
chose the filter, the filter held (:func:`position_hint`) and the linear part after the
hysteresis searched there are both fitted, and the lower validate BIC kept.

The feedforward inverse (:func:`inverse_prefilter`) is approximate: the hysteresis is inverted
for the filter's output, then ``F(s)^-1 (s / wf + 1)^-r`` (``r`` the order of ``F``, ``wf``
:data:`~pimodel.diagnosis.lti.INVERSE_FILTER` times its fastest pole, static gain 1, Tustin,
advanced one sample for the hold) gives the input.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from scipy.signal import bilinear_zpk, lfilter, lfilter_zi, sosfilt, sosfilt_zi, zpk2sos

from ..operators.pi import PIOperator
from .chunked import transposed
from .lti import INVERSE_FILTER, element_coefficients, nelder_mead
from .threads import drop_threads, per_thread

__all__ = ["WienerBasis", "describe_wiener", "inverse_prefilter", "inverse_sections",
           "polish_filter", "position_hint", "prefilter", "search_filter", "wiener_k"]

MIN_HZ = 50.0  # slowest mode [Hz] (a slower filter moves every loop of the record)
LOWPASS_MIN_HZ = 15.0  # slowest low-pass corner [Hz]: an amplifier's bandwidth of 20-50 Hz
LOWPASS_HZ = 8  # points of the low-pass grid, geometric from MIN_HZ to the highest frequency
LOWPASS_SLOW_HZ = (15.0, 22.0, 33.0)  # and these below MIN_HZ
LOWPASS_KINDS = ("lowpass", "lowpass_direct")  # the two samplings of the first-order low-pass
MODE_HZ = 6  # points of the mode grid, likewise
MODE_DAMPING = (0.1, 0.4, 1.0)
GATE = 8.0  # refine a kind only when its grid comes within this factor of the RSS to beat
DAMPING_RANGE = (0.02, 2.0)  # bounds of the refined damping
REFINE_EVALUATIONS = {"lowpass": 12, "lowpass_direct": 12, "mode": 60}  # Nelder-Mead budget per
# kind
POLISH_EVALUATIONS = {"lowpass": 10, "lowpass_direct": 10, "mode": 20}  # then the polish, when
# it is kept
KEPT_COLUMNS = 4  # play-output matrices a WienerBasis keeps (the latest)
ELEMENT_K = {"lowpass": 1, "lowpass_direct": 1, "mode": 2}
KEYS = ("wiener",)  # the grid key of the Wiener variant (its filter elements)


def _check(element) -> str:
    kind = element[0]
    if kind not in ELEMENT_K:
        raise ValueError(f"wiener_elements: expected a kind in {sorted(ELEMENT_K)}, got "
                         f"{kind!r}")
    return kind


def prefilter(v: np.ndarray, elements: Sequence, dt: float) -> np.ndarray:
    """``x = F[v]``: ``v`` through the elements in series, each at rest around ``v[0]``.

    Parameters
    ----------
    v : numpy.ndarray
        Input ``v[k]``.
    elements : sequence
        ``("lowpass", tau [s])``, ``("lowpass_direct", tau [s])`` or ``("mode", fn [Hz],
        zeta)`` (module docstring).
    dt : float
        Sample time [s].

    Returns
    -------
    numpy.ndarray
        ``x[k]``, units of ``v``; ``x[k]`` depends on ``v[0..k-1]`` (on ``v[0..k]`` with a
        ``"lowpass_direct"``).

    Raises
    ------
    ValueError
        An unknown element kind.

    Examples
    --------
    >>> x = prefilter(np.r_[0.0, np.ones(4)], [("lowpass", 1e-3)], 1e-3)
    >>> np.round(x, 4).tolist()
    [0.0, 0.0, 0.6321, 0.8647, 0.9502]
    >>> np.round(prefilter(np.r_[0.0, np.ones(4)], [("lowpass_direct", 1e-3)], 1e-3), 4).tolist()
    [0.0, 0.6321, 0.8647, 0.9502, 0.9817]
    """
    x = np.asarray(v, float)
    for el in elements:
        _check(el)
        b, a = element_coefficients(tuple(el), dt)
        x = lfilter(b, a, x, zi=lfilter_zi(b, a) * x[0])[0]
    return x


def wiener_k(elements: Sequence) -> int:
    """Parameters of the filter (1 per low-pass, 2 per mode).

    Parameters
    ----------
    elements : sequence
        The filter's elements.

    Returns
    -------
    int

    Examples
    --------
    >>> wiener_k([("mode", 400.0, 0.7)])
    2
    """
    return sum(ELEMENT_K[_check(e)] for e in elements)


def describe_wiener(elements: Sequence) -> dict:
    """The filter as plain data for a report.

    Parameters
    ----------
    elements : sequence
        The filter's elements.

    Returns
    -------
    dict
        ``dynamics_position`` (``"before"``), ``wiener_elements`` (JSON lists),
        ``dynamics_order`` (the filter's order), and ``lowpass_hz`` (a low-pass's corner) with
        ``lowpass_sampling`` (``"start"`` or ``"end of hold"``) or ``dynamics_modes`` (a
        mode's ``hz`` and ``damping``).

    Examples
    --------
    >>> d = describe_wiener([("lowpass", 1 / (2 * np.pi * 300.0))])
    >>> d["dynamics_position"], d["dynamics_order"], round(d["lowpass_hz"], 6)
    ('before', 1, 300.0)
    """
    out: dict = {"dynamics_position": "before",
                 "wiener_elements": [[e[0], *(float(x) for x in e[1:])] for e in elements],
                 "dynamics_order": sum(1 if _check(e) in LOWPASS_KINDS else 2 for e in elements)}
    for e in elements:
        if e[0] in LOWPASS_KINDS:
            out["lowpass_hz"] = 1.0 / (2 * np.pi * float(e[1]))
            out["lowpass_sampling"] = "end of hold" if e[0] == "lowpass_direct" else "start"
        else:
            out.setdefault("dynamics_modes", []).append({"hz": float(e[1]),
                                                         "damping": float(e[2])})
    return out


class WienerBasis:
    """One record's play outputs of ``F[v]`` for a filter ``F``, projected like the record's
    play columns (:func:`pimodel.diagnosis.diagnose` may replace the plays by a few
    combinations ``Z V``).

    Parameters
    ----------
    v : numpy.ndarray
        Input ``v[k]``.
    radii : array_like
        Play radii of the diagnosis' grid [input units].
    projection : numpy.ndarray or None
        ``V``, shape (n, q): the record's columns are ``Z V``; None: the plays themselves.
    dt : float
        Sample time [s].
    at_rest : bool
        The plays at rest at the filtered input's first sample (default), else at 0, as the
        nominal's plays (:func:`.effects.make_segment`).

    Examples
    --------
    >>> basis = WienerBasis(np.array([0.0, 1.0, 1.0]), [0.0, 0.5], None, 1e-3)
    >>> basis.columns([("lowpass", 1e-3)]).round(4).tolist()
    [[0.0, 0.0], [0.0, 0.0], [0.6321, 0.1321]]
    """

    _cache = per_thread("cache", dict)  # the kept columns, per thread (module threads)

    def __getstate__(self) -> dict:
        return drop_threads(self.__dict__)

    def __init__(self, v: np.ndarray, radii, projection: np.ndarray | None, dt: float, *,
                 at_rest: bool = True):
        self.v, self.dt = np.asarray(v, float), float(dt)
        self.at_rest = at_rest
        self.radii = np.asarray(radii, float)
        self.projection = projection

    def columns(self, elements: Sequence, ncols: int | None = None) -> np.ndarray:
        """The play columns of ``F[v]`` (the leading ``ncols`` of them; None: all).

        Parameters
        ----------
        elements : sequence
            The filter's elements.
        ncols : int, optional
            Leading columns only (the grid searches use a few).

        Returns
        -------
        numpy.ndarray
            Shape (N, q) or (N, ncols): ``Gamma[F[v]] V`` (plays at rest at ``F[v][0]`` or at
            0, as the plays of ``v`` in :func:`.effects.make_segment`).
        """
        key = (tuple(tuple(e) for e in elements), ncols)
        if key not in self._cache:
            x = prefilter(self.v, elements, self.dt)
            z0 = float(x[0]) if self.at_rest else 0.0
            Z = PIOperator(np.ones(self.radii.size), self.radii,
                           initial_state=z0).play_outputs(x)
            if self.projection is not None:
                Z = Z @ (self.projection if ncols is None else self.projection[:, :ncols])
            elif ncols is not None:
                Z = Z[:, :ncols]
            if len(self._cache) >= KEPT_COLUMNS:
                self._cache.pop(next(iter(self._cache)))
            self._cache[key] = transposed(Z)  # kept as rows, the fits' layout
        return self._cache[key].T

    def release(self) -> None:
        """Drop the memoised play columns (rebuilt on the next use).

        Examples
        --------
        >>> basis = WienerBasis(np.array([0.0, 1.0, 1.0]), [0.0, 0.5], None, 1e-3)
        >>> a = basis.columns([("lowpass", 1e-3)]); basis.release()
        >>> bool(np.array_equal(a, basis.columns([("lowpass", 1e-3)])))
        True
        """
        self._cache.clear()


def _admissible(element, fmax: float) -> bool:
    if element[0] in LOWPASS_KINDS:
        return LOWPASS_MIN_HZ <= 1.0 / (2 * np.pi * element[1]) <= fmax
    return MIN_HZ <= element[1] <= fmax and DAMPING_RANGE[0] <= element[2] <= DAMPING_RANGE[1]


def _grid(fmax: float) -> dict:
    corners = [*(f for f in LOWPASS_SLOW_HZ if f < MIN_HZ), *np.geomspace(MIN_HZ, fmax,
                                                                          LOWPASS_HZ)]
    out = {kind: [(kind, float(1 / (2 * np.pi * f))) for f in corners]
           for kind in LOWPASS_KINDS}
    out["mode"] = [("mode", float(f), z) for f in np.geomspace(2 * MIN_HZ, fmax, MODE_HZ)
                   for z in MODE_DAMPING]
    return out


def search_filter(rss_of: Callable, fmax: float, n: int, rss_to_beat: float | None = None,
                  kinds: Sequence[str] | None = None) -> tuple[tuple, float, int]:
    """The filter with the lowest train BIC (module docstring).

    Parameters
    ----------
    rss_of : callable
        ``rss_of(elements) -> float``: the train RSS of the fit with that filter.
    fmax : float
        Highest corner or mode frequency [Hz] (at least ``MIN_HZ``).
    n : int
        Number of fitted train samples (for the BIC).
    rss_to_beat : float, optional
        The train RSS of the alternative (the Hammerstein variant, scored the same way): a
        kind whose best grid point is more than ``GATE`` times above it is not refined (it
        cannot win; this spares the refinement on a stage whose dynamics follow the
        hysteresis).
    kinds : sequence of str, optional
        The kinds searched (``"lowpass"``, ``"lowpass_direct"``, ``"mode"``); None: all.

    Returns
    -------
    elements : tuple
        One element, ``(("lowpass", tau),)`` or ``(("mode", fn, zeta),)``.
    rss : float
        Its train RSS.
    k : int
        Its parameters (:func:`wiener_k`).

    Raises
    ------
    ValueError
        ``fmax`` below ``MIN_HZ``; ``kinds`` empty or naming an unknown kind.

    Examples
    --------
    A quadratic bowl around a 300 Hz low-pass:

    >>> tau0 = 1 / (2 * np.pi * 300.0)
    >>> def rss_of(els):
    ...     e = els[0]
    ...     return 1.0 + (np.log(e[1] / tau0) ** 2 if e[0] == "lowpass" else 5.0)
    >>> els, rss, k = search_filter(rss_of, 2000.0, 1000)
    >>> els[0][0], round(1 / (2 * np.pi * els[0][1]), -1), k
    ('lowpass', 300.0, 1)
    """
    if not fmax >= MIN_HZ:
        raise ValueError(f"fmax: expected >= {MIN_HZ} Hz, got {fmax!r}")
    if kinds is not None and (not kinds or set(kinds) - set(ELEMENT_K)):
        raise ValueError(f"kinds: expected some of {sorted(ELEMENT_K)}, got {kinds!r}")
    best = None
    for kind, grid in _grid(fmax).items():
        if kinds is not None and kind not in kinds:
            continue
        scored = [(el, rss_of((el,))) for el in grid if _admissible(el, fmax)]
        el, rss = min(scored, key=lambda o: o[1])
        if rss_to_beat is None or rss < GATE * rss_to_beat:
            el, rss = _refine(rss_of, el, rss, fmax, REFINE_EVALUATIONS[kind], (0.2, 0.3))
        k = ELEMENT_K[kind]
        score = n * np.log(max(rss, 1e-300) / n) + k * np.log(n)
        if best is None or score < best[0]:
            best = (score, (el,), rss, k)
    return best[1], best[2], best[3]


def _refine(rss_of: Callable, el0: tuple, rss0: float, fmax: float, maxfev: int,
            steps: tuple) -> tuple[tuple, float]:
    """Nelder-Mead on the log parameters of one element from ``el0`` (``rss0`` its RSS)."""
    kind = el0[0]
    x0 = np.log(np.asarray(el0[1:], float))

    def cost(x):
        el = (kind, *(float(u) for u in np.exp(x)))
        return rss_of((el,)) if _admissible(el, fmax) else np.inf

    step = [steps[0]] if kind in LOWPASS_KINDS else [0.5 * steps[0], steps[1]]
    simplex = [x0] + [x0 + np.eye(x0.size)[i] * s for i, s in enumerate(step)]
    r = nelder_mead(cost, x0, initial_simplex=simplex, xatol=1e-4, fatol=1e-7 * rss0,
                    maxfev=maxfev)
    if r.fun < rss0:
        return (kind, *(float(u) for u in np.exp(r.x))), float(r.fun)
    return el0, rss0


def polish_filter(rss_of: Callable, elements: tuple, rss: float,
                  fmax: float) -> tuple[tuple, float]:
    """A short Nelder-Mead polish of a filter found by :func:`search_filter` on the fit with
    every column; a low-pass is also polished in its other sampling (``"lowpass"``,
    ``"lowpass_direct"``) from the same corner, the lower RSS kept.

    Parameters
    ----------
    rss_of : callable
        ``rss_of(elements) -> float``: the train RSS of the full fit.
    elements : tuple
        The filter found (one element).
    rss : float
        Its train RSS with every column.
    fmax : float
        Highest corner or mode frequency [Hz].

    Returns
    -------
    elements : tuple
        The polished filter (``elements`` if nothing is lower).
    rss : float
        Its train RSS.

    Examples
    --------
    >>> tau0 = 1 / (2 * np.pi * 300.0)
    >>> els, rss = polish_filter(lambda e: 1.0 + np.log(e[0][1] / tau0) ** 2,
    ...                          (("lowpass", 1.05 * tau0),), 1.0 + np.log(1.05) ** 2, 2000.0)
    >>> round(els[0][1] / tau0, 2)
    1.0
    """
    el, rss = _refine(rss_of, tuple(elements[0]), rss, fmax,
                      POLISH_EVALUATIONS[elements[0][0]], (0.03, 0.1))
    if el[0] in LOWPASS_KINDS:
        # the other sampling of the low-pass from the same corner: on the leading columns of
        # the search the two differ little (a sample of lag against a slightly faster
        # corner), with every column the right one fits to the noise (bw49: a 108 Hz
        # amplifier sampled at the end of the hold kept as a 124 Hz ZOH low-pass)
        other = (LOWPASS_KINDS[el[0] == "lowpass"], el[1])
        el2, rss2 = _refine(rss_of, other, rss_of((other,)), fmax,
                            POLISH_EVALUATIONS[other[0]], (0.03, 0.1))
        if rss2 < rss:
            el, rss = el2, rss2
    return (el,), rss


def position_hint(alone_grid: dict) -> dict:
    """The grid parameters that hold the Wiener variant when ``dynamics`` is fitted beside
    other effects (one of the two variants scored there): those of the ``dynamics`` candidate
    alone when it chose it, else none.

    Parameters
    ----------
    alone_grid : dict
        The grid parameters of the ``dynamics`` candidate fitted alone (``Model.grid``).

    Returns
    -------
    dict
        ``{"wiener": elements}`` or ``{}``.

    Examples
    --------
    >>> position_hint({"wiener": (("lowpass", 1e-3),)}), position_hint({"fn": 900.0})
    ({'wiener': (('lowpass', 0.001),)}, {})
    """
    return {k: alone_grid[k] for k in KEYS if k in alone_grid}


def inverse_sections(elements: Sequence, dt: float) -> np.ndarray | None:
    """Second-order sections of the stable approximate inverse of the filter ``F`` (module
    docstring), before its one-sample advance; None for an empty filter.

    Parameters
    ----------
    elements : sequence
        The filter's elements.
    dt : float
        Sample time [s].

    Returns
    -------
    numpy.ndarray or None
        ``sos`` of shape ``(s, 6)`` (:func:`scipy.signal.sosfilt` form), static gain 1: what
        :func:`inverse_prefilter` runs and the inverse block
        (:mod:`~pimodel.diagnosis.native_inverse`, its reference
        :mod:`~pimodel.diagnosis.reference_inverse`) steps through.

    Raises
    ------
    ValueError
        An unknown element kind.

    Examples
    --------
    >>> sos = inverse_sections([("lowpass", 1e-3)], 1e-4)
    >>> sos.shape, round(float(np.sum(sos[0, :3]) / np.sum(sos[0, 3:])), 12)
    ((1, 6), 1.0)
    """
    poles, advanced = [], 0
    for e in elements:
        if _check(e) in LOWPASS_KINDS:
            poles.append(np.array([-1.0 / float(e[1])]))
            advanced += e[0] == "lowpass_direct"
        else:
            w, z = 2 * np.pi * float(e[1]), float(e[2])
            poles.append(np.roots([1.0, 2 * z * w, w * w]))
    p = np.concatenate(poles) if poles else np.zeros(0)
    if p.size == 0:
        return None
    wf = INVERSE_FILTER * float(np.max(np.abs(p)))
    p_inv = np.full(p.size, -wf)
    k = float(np.real(np.prod(-p_inv) / np.prod(-p)))  # static gain 1
    sos = zpk2sos(*bilinear_zpk(p, p_inv, k, fs=1.0 / dt))
    # a "lowpass_direct" is the ZOH form advanced one sample: a sample of delay in its inverse
    # (a section z^-1), which the inverse's one-sample advance then cancels
    return np.vstack([sos] + [[0.0, 1.0, 0.0, 1.0, 0.0, 0.0]] * advanced)


def inverse_prefilter(x: np.ndarray, elements: Sequence, dt: float) -> np.ndarray:
    """``x`` through a stable approximate inverse of the filter ``F`` (module docstring).

    Parameters
    ----------
    x : numpy.ndarray
        Desired filter output ``x[k]`` (the hysteresis' input), every ``dt``.
    elements : sequence
        The filter's elements.
    dt : float
        Sample time [s].

    Returns
    -------
    numpy.ndarray
        The input ``v[k]`` (started at rest around ``x[0]``); ``v[k]`` depends on
        ``x[0..k+1]``, the last sample held.

    Examples
    --------
    >>> t = np.arange(4000) * 1e-4
    >>> v = np.sin(2 * np.pi * 5 * t)
    >>> x = prefilter(v, [("lowpass", 1e-3)], 1e-4)
    >>> err = np.abs(inverse_prefilter(x, [("lowpass", 1e-3)], 1e-4) - v)[:-1]
    >>> bool(np.max(err) < 0.02)  # the added low-pass at 318 Hz lags 5 Hz by about 1 degree
    True
    """
    sos = inverse_sections(elements, dt)
    if sos is None:
        return np.asarray(x, float)
    out = sosfilt(sos, x, zi=sosfilt_zi(sos) * x[0])[0]
    return np.r_[out[1:], out[-1]]
