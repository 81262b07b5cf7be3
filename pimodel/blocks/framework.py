"""The block framework every pimodel python-control block is built on.

A pimodel block is a :class:`Block` (a ``control.NonlinearIOSystem`` that knows its own
initial state), made by :func:`stepped_block` from a per-sample ``step`` and a
:class:`BlockSettings` (the block's parameters in python-control's ``params`` dict under
``"<block name>.<setting>"``). :func:`initial_state` returns a block's (or an
interconnection's) own initial state; :func:`signal_labels` names vector signals 1-based
(``z[1]..z[n]``). Semantics (python-control's for discrete systems): the output is
``outfcn(t, x[k], u[k])`` and ``updfcn`` returns ``x[k+1]``.
"""

from __future__ import annotations

import operator
import warnings
from collections.abc import Callable

import control
import numpy as np

__all__ = [
    "Block",
    "BlockSettings",
    "InitialStateWarning",
    "initial_state",
    "labelled_values",
    "signal_labels",
    "stepped_block",
    "warn_if_zero_start",
]


class InitialStateWarning(UserWarning):
    """A block is simulated from a state that is not its own initial state (typically
    python-control's default of zeros); pass ``initial_state=initial_state(sys)``.

    Examples
    --------
    >>> import warnings, control
    >>> from pimodel import PIOperator
    >>> from pimodel.blocks import pi_block
    >>> pb = pi_block(PIOperator([1.0, 0.5], [0.0, 0.3], initial_state=0.7), 1e-3)
    >>> t = np.arange(3) * 1e-3
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     _ = control.input_output_response(pb, t, 0 * t)   # X0 = 0 is not the block's state
    >>> any(issubclass(w.category, InitialStateWarning) for w in caught)
    True
    """


class Block(control.NonlinearIOSystem):
    """A pimodel block: a ``NonlinearIOSystem`` that knows its own initial state.

    Parameters
    ----------
    updfcn, outfcn : callable
        python-control's ``updfcn(t, x, u, params) -> x[k+1]`` and
        ``outfcn(t, x, u, params) -> y[k]``.
    own_state : callable
        ``own_state(params) -> x0``: the block's own initial state for the given params (what
        :func:`initial_state` returns).
    aliases : dict, optional
        Deprecated state names mapped to current ones (old result keys keep working).
    **kwargs
        Passed to ``control.NonlinearIOSystem`` (``inputs``, ``outputs``, ``states``, ``dt``,
        ``name``, ``params``).

    Examples
    --------
    >>> import numpy as np
    >>> b = Block(lambda t, x, u, p: x + u, lambda t, x, u, p: x, own_state=lambda p: [1.0],
    ...           inputs=["u"], outputs=["y"], states=["x"], dt=1.0, name="acc")
    >>> initial_state(b)
    array([1.])
    """

    def __init__(self, updfcn, outfcn, *, own_state: Callable[[dict], np.ndarray],
                 aliases: dict[str, str] | None = None, **kwargs):
        super().__init__(updfcn, outfcn, **kwargs)
        self._own_state = own_state
        self._aliases = dict(aliases or {})

    @property
    def x0(self) -> np.ndarray:
        """Deprecated: use ``pimodel.blocks.initial_state(sys)``."""
        warnings.warn("sys.x0 is deprecated; use pimodel.blocks.initial_state(sys) and pass it "
                      "as initial_state= to control.input_output_response",
                      DeprecationWarning, stacklevel=2)
        return self._own_state(self.params)


def stepped_block(settings: BlockSettings, step: Callable, *,
                  own_state: Callable[[dict], np.ndarray],
                  states: list[str], dt: float, name: str, input: str, output: str,
                  memo: bool = False) -> control.NonlinearIOSystem:
    """A discrete one-input, one-output block around one sample function.

    ``step(obj, x, u, t) -> (y, x_next)`` with ``obj = settings.get(params)`` (the object the
    block's settings build), ``x`` a float copy of the state after sample k - 1 (``step`` may
    advance it in place and return it), ``u`` the input sample and ``t`` python-control's time:
    ``outfcn`` gives ``y[k]`` (direct feedthrough), ``updfcn`` the state after sample k. With
    ``memo`` the last sample's result is kept, so a dear ``step`` (a root solve) runs once per
    sample although python-control calls ``outfcn`` and ``updfcn`` each.

    Parameters
    ----------
    settings : BlockSettings
        The block's settings; ``settings.get(params)`` is the object passed to ``step``.
    step : callable
        ``step(obj, x, u, t) -> (y, x_next)``, one sample.
    own_state : callable
        ``own_state(params) -> x0``, the block's own initial state.
    states : list of str
        State names (use :func:`signal_labels` for vectors).
    dt : float
        Sample time [s].
    name, input, output : str
        Block name and its one input and one output signal.
    memo : bool, optional
        Keep the last sample's result (for a costly ``step``). Default False.

    Returns
    -------
    Block
        The discrete-time block.

    Examples
    --------
    >>> import control, numpy as np
    >>> gain = BlockSettings("g", {"k": 2.0}, lambda s: float(s["k"]))
    >>> blk = stepped_block(gain, lambda k, x, u, t: (k * u + x[0], np.array([u])),
    ...                     own_state=lambda p: np.zeros(1), states=["u_prev"], dt=1.0,
    ...                     name="g", input="u", output="y")
    >>> res = control.input_output_response(blk, np.arange(3.0), [1.0, 2.0, 3.0])
    >>> res.outputs.tolist()
    [2.0, 5.0, 8.0]
    """
    cache: dict = {}

    def run(t, x, u, params):
        obj = settings.get(params)
        if memo:
            key = (np.asarray(x, float).tobytes(), float(u[0]), float(t), id(obj))
            if key not in cache:
                cache.clear()
                cache[key] = step(obj, np.array(x, dtype=float), float(u[0]), float(t))
            return cache[key]
        return step(obj, np.array(x, dtype=float), float(u[0]), float(t))

    def upd(t, x, u, params):
        return run(t, x, u, params)[1]

    def out(t, x, u, params):
        return np.array([run(t, x, u, params)[0]])

    return Block(upd, out, own_state=own_state, inputs=[input], outputs=[output],
                  states=states, dt=dt, name=name, params=settings.params)


def signal_labels(base: str, n: int) -> list[str]:
    """1-based labels of a vector signal, ``base[1]..base[n]`` (as the FMUs and the paper).

    Parameters
    ----------
    base : str
        The signal's name.
    n : int
        Its length.

    Returns
    -------
    list of str
        ``n`` labels.

    Examples
    --------
    >>> signal_labels("z", 3)
    ['z[1]', 'z[2]', 'z[3]']
    """
    return [f"{base}[{i}]" for i in range(1, n + 1)]


def labelled_values(base: str, values, *, split: int | None = None) -> dict[str, float]:
    """The values of a vector by their 1-based labels, ``{"base[1]": values[0], ...}`` (the
    FMU variables' names).

    Parameters
    ----------
    base : str
        The vector's name.
    values : array_like
        Its values.
    split : int, optional
        Values beyond the first ``split`` go to ``base_hi[1], base_hi[2], ...`` (the diagnosed
        units' plays 65..128). Default: all in ``base[i]``.

    Returns
    -------
    dict
        Label -> float.

    Examples
    --------
    >>> labelled_values("p", [1.0, 0.5])
    {'p[1]': 1.0, 'p[2]': 0.5}
    >>> labelled_values("r", [0.0, 0.1, 0.2], split=2)
    {'r[1]': 0.0, 'r[2]': 0.1, 'r_hi[1]': 0.2}
    """
    out = {}
    for i, x in enumerate(np.asarray(values, dtype=float).ravel()):
        hi = split is not None and i >= split
        out[f"{base}_hi[{i - split + 1}]" if hi else f"{base}[{i + 1}]"] = float(x)
    return out


def _fingerprint(value):
    """A cheap, comparable summary of a setting's value (arrays by their bytes, so a setting
    changed in place is seen as changed)."""
    if isinstance(value, (list, tuple)):
        try:
            value = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            return repr(value)
    if isinstance(value, np.ndarray):
        return value.dtype.str, value.shape, value.tobytes()
    return value


def _immutable(value) -> bool:
    """True for values that cannot change in place (so the same object means the same value)."""
    if isinstance(value, np.ndarray):
        return not value.flags.writeable
    return value is None or isinstance(value, (bool, int, float, str, np.generic))


class BlockSettings:
    """A block's settings read from python-control's ``params`` under ``"<name>.<setting>"``.

    ``build(settings)`` validates them and returns what the update function needs; it runs at
    construction and again only when a value changes, so reading params costs a comparison of
    fingerprints (a few microseconds).

    Parameters
    ----------
    name : str
        The block's name (the params prefix).
    defaults : dict
        Setting name -> value at construction (the block's ``sys.params``).
    build : callable
        ``build(values) -> object``; raises ValueError or TypeError on a bad value.

    Examples
    --------
    >>> s = BlockSettings("pi", {"gain": 2.0}, lambda v: 10 * v["gain"])
    >>> s.get({}), s.get({"pi.gain": 3.0}), s.params
    (20.0, 30.0, {'pi.gain': 2.0})
    """

    def __init__(self, name: str, defaults: dict, build: Callable[[dict], object]):
        self.name = name
        self.defaults = {k: np.array(v, dtype=float) if isinstance(v, (list, np.ndarray)) else v
                         for k, v in defaults.items()}
        for v in self.defaults.values():
            if isinstance(v, np.ndarray):
                v.setflags(write=False)  # shared through sys.params: never changed in place
        self._default_fp = {k: _fingerprint(v) for k, v in self.defaults.items()}
        self.keys = {k: f"{name}.{k}" for k in self.defaults}
        self._lookup = [(self.keys[k], v) for k, v in self.defaults.items()]
        self.build = build
        self._known = set(self.keys.values())
        self._last_keys: set = set()
        self._last_params = None
        self._seen = tuple(self._default_fp.values())
        self._objs = list(self.defaults.values())
        self._immutable = all(_immutable(v) for v in self._objs)
        self.value = self._build(self.defaults)

    @property
    def params(self) -> dict:
        return {self.keys[k]: v for k, v in self.defaults.items()}

    def _build(self, values: dict):
        try:
            return self.build(values)
        except (ValueError, TypeError) as err:  # a wrong type in params is a bad value too
            raise ValueError(f"block {self.name!r}, params {sorted(self._known)}: "
                             f"{err}") from err

    def _check_names(self, params: dict) -> None:
        if len(params) == len(self._last_keys) and params.keys() == self._last_keys:
            return
        prefix = f"{self.name}."
        unknown = [k for k in params if isinstance(k, str) and k.startswith(prefix)
                   and k not in self._known]
        if unknown:
            raise ValueError(f"params: unknown setting(s) {sorted(unknown)} for block "
                             f"{self.name!r}; known: {sorted(self._known)}")
        self._last_keys = set(params.keys())

    def get(self, params: dict | None):
        """The built settings for ``params`` (missing keys: construction values).

        Parameters
        ----------
        params : dict or None
            python-control's params (keys ``"<name>.<setting>"``).

        Returns
        -------
        object
            What ``build`` returned for these values (cached while they do not change).

        Raises
        ------
        ValueError
            An unknown ``"<name>.*"`` key, or a value ``build`` refuses.

        Examples
        --------
        >>> BlockSettings("b", {"k": 1.0}, lambda v: v["k"] + 1).get({"b.k": 4.0})
        5.0
        """
        params = params or {}
        if params is self._last_params and self._immutable:
            return self.value  # python-control passes one dict to a block's every call
        self._check_names(params)
        self._last_params = params
        objs = [params.get(key, default) for key, default in self._lookup]
        if self._immutable and all(map(operator.is_, objs, self._objs)):
            return self.value  # the same unchangeable objects as last time
        values = dict(zip(self.keys, objs, strict=True))
        seen = tuple(self._default_fp[k] if v is self.defaults[k] else _fingerprint(v)
                     for k, v in values.items())
        if seen != self._seen:
            self.value = self._build(values)
            self._seen = seen
        self._objs = objs
        self._immutable = all(_immutable(v) for v in objs)
        return self.value


def warn_if_zero_start(name: str, t, x, own: np.ndarray) -> None:
    """Cheap first-sample check: warn when ``x`` is all zeros at t = 0 while the block's own
    state is not (python-control's default initial state used by mistake).

    Parameters
    ----------
    name : str
        The block's name (for the message).
    t : float
        python-control's time.
    x : array_like
        The state python-control passes.
    own : numpy.ndarray
        The block's own initial state.

    Examples
    --------
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     warn_if_zero_start("pi", 0.0, [0.0], np.array([0.5]))
    >>> caught[0].category.__name__
    'InitialStateWarning'
    """
    if t == 0 and np.any(own) and not np.any(x):
        warnings.warn(f"block {name!r} starts from an all-zero state but its own initial state "
                      f"is {np.array2string(np.asarray(own), precision=4)}; pass "
                      "initial_state=pimodel.blocks.initial_state(sys) to "
                      "control.input_output_response", InitialStateWarning, stacklevel=3)


def initial_state(sys: control.InputOutputSystem, params: dict | None = None) -> np.ndarray:
    """The initial state vector ``X0`` of a pimodel block or of an interconnection of blocks.

    Pass it to python-control as ``initial_state=`` (``X0``). For an ``interconnect`` the
    vector is assembled from ``sys.syslist`` in the interconnection's state order; pimodel
    blocks give their own initial state (computed from ``params`` as python-control merges
    them: block defaults, then the interconnection's, then ``params``), other systems zeros.

    Parameters
    ----------
    sys : control.InputOutputSystem
        A block from :mod:`pimodel.blocks`, :func:`pimodel.fmu.block.fmu_block`, any
        python-control system, or an interconnection of them.
    params : dict, optional
        The params that will be passed to the simulation (settings such as
        ``"<block>.initial_state"`` or ``"<block>.initial_radii"`` define the initial state).

    Returns
    -------
    numpy.ndarray
        ``sys.nstates`` values, labelled by ``sys.state_labels``.

    Examples
    --------
    >>> import control, numpy as np
    >>> from pimodel import PIOperator
    >>> from pimodel.blocks import pi_block, initial_state
    >>> pb = pi_block(PIOperator([1, 0.5], [0, 0.3], initial_state=0.7), 1e-3)
    >>> t = np.arange(5) * 1e-3
    >>> res = control.input_output_response(pb, t, 0 * t, initial_state=initial_state(pb))
    >>> float(res.outputs[0])
    0.15
    """
    params = dict(params or {})
    own = getattr(sys, "_own_state", None)
    if own is not None:
        merged = {**sys.params, **params}
        return np.asarray(own(merged), float).reshape(sys.nstates).copy()
    subs = getattr(sys, "syslist", None)
    if subs is not None:
        x0 = np.zeros(sys.nstates)
        for sub, offset in zip(subs, sys.state_offset, strict=True):
            local = {**sub.params, **sys.params, **params}
            x0[offset:offset + sub.nstates] = initial_state(sub, local)
        return x0
    if hasattr(sys, "x0"):  # a user's own system with the old ad-hoc attribute
        warnings.warn(f"{sys.name}: the x0 attribute is deprecated; give the system's initial "
                      "state to control.input_output_response directly", DeprecationWarning,
                      stacklevel=2)
        return np.broadcast_to(np.asarray(sys.x0, float), (sys.nstates,)).copy()
    return np.zeros(sys.nstates)
