"""What a model file holds, as one object: :class:`Model` (operator, offset, sample time, units,
provenance) and its feedforward :class:`ModelInverse`.

Discrete-time semantics: ``y[k] = H[v][k] + offset`` with ``H`` the operator stepped from its
initial state; the inverse is ``v[k] = H^-1[y_d - offset][k]``. A
:class:`~pimodel.diagnosis.model.DiagnosedModel` carries its own offset (the file's ``offset``
key), so nothing is added to it a second time.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..operators.cascade import Cascade
from ..operators.envelopes import Envelope
from ..operators.generalized import GeneralizedPI
from ..operators.pi import PIOperator
from .codec import _operator, model_to_dict
from .schema import FORMAT_VERSION, check_model_dict

__all__ = ["Model", "ModelInverse"]


def _own_offset(operator) -> bool:
    """True for a model type whose JSON form has its own ``offset`` (DiagnosedModel)."""
    return type(operator).__name__ == "DiagnosedModel"


@dataclass
class Model:
    """A model file's content: ``y[k] = operator[v][k] + offset``.

    Parameters
    ----------
    operator : object
        An operator, an inverse, a Cascade or a DiagnosedModel (``pimodel.model_files``).
    offset : float
        Output offset [output unit] added to the operator's output (a DiagnosedModel: its own
        offset, not added again).
    dt : float or None
        Sample time [s] of the record the model came from (None: not known).
    units : dict
        ``time``, ``input``, ``output`` unit names (strings), as far as known.
    provenance : dict
        ``record``, ``columns``, ``method``, ``date``, ``pimodel_version``, ``source``.
    report : dict or None
        What the method reported (``pimodel identify``: fit, excitation, slopes, health).

    Examples
    --------
    >>> m = Model(PIOperator([1.0, 0.5], [0.0, 0.3]), offset=2.0)
    >>> m.simulate([0.0, 1.0]).tolist()
    [2.0, 3.35]
    >>> m.inverse().simulate([2.0, 3.35]).round(12).tolist()
    [0.0, 1.0]
    """

    operator: object
    offset: float = 0.0
    dt: float | None = None
    units: dict = field(default_factory=dict)
    provenance: dict = field(default_factory=dict)
    report: dict | None = None

    def __post_init__(self) -> None:
        if _own_offset(self.operator):
            self.offset = float(self.operator.offset)
            self.dt = float(self.operator.dt)
        self.offset = float(self.offset)

    @classmethod
    def from_dict(cls, d: dict, *, where: str = "model") -> Model:
        """Check ``d`` against the schema and build the model with its metadata.

        Parameters
        ----------
        d : dict
            A model file's JSON object.
        where : str
            Name of ``d`` in error messages.

        Returns
        -------
        Model

        Raises
        ------
        ValueError
            Naming the key and what was expected (:func:`.schema.check_model_dict`).
        """
        check_model_dict(d, where=where)
        op = _operator(d, where)
        return cls(op, offset=d.get("offset", 0.0), dt=d.get("dt"),
                   units=dict(d.get("units", {})), provenance=dict(d.get("provenance", {})),
                   report=d.get("report"))

    def as_file_dict(self) -> dict:
        """The model file's JSON object: the operator's form plus ``offset``, ``dt``, ``units``,
        ``provenance``, ``report`` and ``format_version``.

        Returns
        -------
        dict

        Examples
        --------
        >>> d = Model(PIOperator([2.0], [0.0]), offset=1.0, dt=1e-3).as_file_dict()
        >>> d["type"], d["offset"], d["dt"], d["format_version"]
        ('PIOperator', 1.0, 0.001, 2)
        """
        d = model_to_dict(self.operator)
        d.setdefault("offset", self.offset)
        if self.dt is not None:
            d.setdefault("dt", float(self.dt))
        for key in ("units", "provenance"):
            if getattr(self, key):
                d[key] = dict(getattr(self, key))
        if self.report is not None:
            d["report"] = self.report
        d["format_version"] = FORMAT_VERSION
        return d

    @property
    def added_offset(self) -> float:
        """What :meth:`simulate` adds to the operator's output (0 for a DiagnosedModel)."""
        return 0.0 if _own_offset(self.operator) else self.offset

    def simulate(self, v, *args, **kwargs) -> np.ndarray:
        """``y[k] = operator[v][k] + offset`` from the operator's initial state.

        Parameters
        ----------
        v : array_like
            Input samples ``v[k]``.
        *args, **kwargs
            Passed to the operator's ``simulate`` (e.g. ``t`` of a DiagnosedModel).

        Returns
        -------
        numpy.ndarray
            ``y[k]`` [output unit].

        Examples
        --------
        >>> Model(PIOperator([2.0], [0.0]), offset=1.0).simulate([0.0, 0.5]).tolist()
        [1.0, 2.0]
        """
        return np.asarray(self.operator.simulate(v, *args, **kwargs)) + self.added_offset

    def step(self, v: float) -> float:
        """One sample ``y[k]`` of the input ``v[k]`` (the operator's state advances).

        Parameters
        ----------
        v : float
            ``v[k]``.

        Returns
        -------
        float
            ``y[k]``.

        Examples
        --------
        >>> Model(PIOperator([2.0], [0.0]), offset=1.0).step(0.5)
        2.0
        """
        return float(self.operator.step(v)) + self.added_offset

    def reset(self) -> None:
        """Back to the operator's initial state.

        Examples
        --------
        >>> m = Model(PIOperator([2.0], [0.0]), offset=1.0)
        >>> m.step(0.5), m.reset(), m.step(0.0)
        (2.0, None, 1.0)
        """
        self.operator.reset()

    def inverse(self) -> ModelInverse:
        """The feedforward ``v[k] = operator^-1[y_d - offset][k]`` (:class:`ModelInverse`).

        Returns
        -------
        ModelInverse

        Examples
        --------
        >>> Model(PIOperator([2.0], [0.0]), offset=1.0).inverse().simulate([1.0, 2.0]).tolist()
        [0.0, 0.5]
        """
        return ModelInverse(self.operator.inverse(), self.added_offset, self.operator)

    def as_operator(self):
        """One operator equal to :meth:`simulate`, for the FMU builders.

        Without an added offset: the operator itself. A PIOperator with an offset: a
        GeneralizedPI with the offset as an affine output envelope; any other operator: a
        Cascade of it and an offset stage (a one-play GeneralizedPI of radius 0, ``y = v +
        offset``).

        Returns
        -------
        object

        Examples
        --------
        >>> Model(PIOperator([2.0], [0.0]), offset=1.0).as_operator().output_envelope
        Envelope('poly2', [1.0, 1.0, 0.0])
        """
        op, c = self.operator, self.added_offset
        if c == 0.0:
            return op
        env = Envelope.affine(1.0, c)
        if type(op) is PIOperator:
            state = op.initial_state
            return GeneralizedPI(op.weights, op.radii, output_envelope=env,
                                 initial_state=float(state[0]) if np.all(state == state[0])
                                 else state, signed_weights=bool(np.any(op.weights <= 0)))
        shift = GeneralizedPI([1.0], [0.0], output_envelope=env)
        stages = op.stages if isinstance(op, Cascade) else (op,)
        return Cascade(*stages, shift)

    def __getattr__(self, name: str):
        if name.startswith("__") or name == "operator":
            raise AttributeError(name)
        return getattr(self.operator, name)


class ModelInverse:
    """The feedforward of a :class:`Model`: ``v[k] = inverse[y_d[k] - offset]``.

    Parameters
    ----------
    inverse : object
        The operator's inverse.
    offset : float
        The model's added offset, subtracted from ``y_d`` first.
    forward : object, optional
        The forward operator (for :meth:`as_operator`).

    Examples
    --------
    >>> inv = Model(PIOperator([2.0], [0.0]), offset=1.0).inverse()
    >>> inv.simulate([1.0, 3.0]).tolist()
    [0.0, 1.0]
    """

    def __init__(self, inverse, offset: float, forward=None) -> None:
        self.operator = inverse
        self.offset = float(offset)
        self.forward = forward

    def simulate(self, y_d, *args, **kwargs) -> np.ndarray:
        """``v[k]`` for the desired outputs ``y_d[k]``.

        Parameters
        ----------
        y_d : array_like
            Desired output samples [output unit].
        *args, **kwargs
            Passed to the inverse's ``simulate``.

        Returns
        -------
        numpy.ndarray
            ``v[k]`` [input unit].

        Examples
        --------
        >>> Model(PIOperator([2.0], [0.0]), offset=1.0).inverse().simulate([3.0]).tolist()
        [1.0]
        """
        return np.asarray(self.operator.simulate(np.asarray(y_d, float) - self.offset,
                                                 *args, **kwargs))

    def step(self, y_d: float) -> float:
        """One sample ``v[k]`` of ``y_d[k]``.

        Parameters
        ----------
        y_d : float
            ``y_d[k]``.

        Returns
        -------
        float
            ``v[k]``.

        Examples
        --------
        >>> Model(PIOperator([2.0], [0.0]), offset=1.0).inverse().step(3.0)
        1.0
        """
        return float(self.operator.step(y_d - self.offset))

    def as_operator(self):
        """One operator equal to :meth:`simulate`, for the FMU builders: the inverse itself (no
        offset); a PI operator's with an offset, the inverse of :meth:`Model.as_operator`
        (a GeneralizedPI's exact inverse); another after an offset stage (a Cascade).

        Returns
        -------
        object

        Examples
        --------
        >>> inv = Model(PIOperator([2.0], [0.0]), offset=1.0).inverse().as_operator()
        >>> inv.simulate([3.0]).tolist()
        [1.0]
        """
        op = self.operator
        if type(self.forward) is PIOperator and self.offset != 0.0:
            return Model(self.forward, offset=self.offset).as_operator().inverse()
        if self.offset == 0.0:
            return op
        shift = GeneralizedPI([1.0], [0.0], output_envelope=Envelope.affine(1.0, -self.offset))
        stages = self.operator.stages if isinstance(self.operator, Cascade) else (self.operator,)
        return Cascade(shift, *stages)

    def reset(self) -> None:
        """Back to the inverse's initial state.

        Examples
        --------
        >>> inv = Model(PIOperator([2.0], [0.0]), offset=1.0).inverse()
        >>> inv.step(3.0), inv.reset(), inv.step(1.0)
        (1.0, None, 0.0)
        """
        self.operator.reset()

    def __getattr__(self, name: str):
        if name.startswith("__") or name in ("operator", "forward"):
            raise AttributeError(name)
        return getattr(self.operator, name)
