"""Least squares over a record taken in chunks of samples, so a fit holds the model (a ``p x p``
matrix), not the record's ``N x p`` design matrix.

Two accumulators, both fed the regressors as rows (``X`` of shape (p, m) for ``m`` samples, the
layout the diagnosis builds them in) and the outputs of the same samples:

- :class:`NormalEquations` sums ``X X^T`` and ``X y``; :meth:`~NormalEquations.solve` scales
  the columns to unit norm first (the normal equations square the condition number; scaling
  removes the part due to columns of different size) and solves by least squares with a
  relative cut-off ``rcond``. One pass, ``p^2 m`` flops per chunk: the diagnosis' searches use it.
  With ``y^T y`` summed too, :meth:`~NormalEquations.rss` gives the residual sum of squares from
  the sums where cancellation cannot move it by ``RSS_RTOL`` (else None: a pass over the
  residuals is needed).
- :class:`ChunkedQR` keeps a running triangular factor: each chunk is stacked under the ``R``
  so far (with the output as a last column) and factored again by ``numpy.linalg.qr``, so
  the condition number is never squared; the last diagonal element of the factor gives the
  residual sum of squares. Use it where the normal equations lose digits (``cond(X) > 1e7``).

The chunks are cut by :func:`chunks` (``CHUNK`` samples each).
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
from scipy.linalg.lapack import dgeqrf
from scipy.optimize import lsq_linear

__all__ = ["CHUNK", "RSS_RTOL", "ChunkedQR", "NormalEquations", "chunks", "combine",
           "stack_rows", "transposed"]

CHUNK = 1 << 14  # samples per chunk (16,384: an 80-column chunk of rows is 10 MB)
RSS_RTOL = 1e-8  # NormalEquations.rss: largest relative rounding error accepted
RSS_SAFETY = 4.0  # times the rounding estimate (measured at most 1.5x it on the fits)


def chunks(n: int, size: int = CHUNK) -> Iterator[slice]:
    """Slices ``a:b`` that cut ``range(n)`` into consecutive chunks of ``size`` samples.

    Parameters
    ----------
    n : int
        Samples in all.
    size : int
        Samples per chunk (the last one may be shorter).

    Returns
    -------
    iterator of slice
        ``slice(0, size), slice(size, 2 size), ...`` up to ``n``.

    Raises
    ------
    ValueError
        ``size`` below 1 or ``n`` negative.

    Examples
    --------
    >>> list(chunks(5, 2))
    [slice(0, 2, None), slice(2, 4, None), slice(4, 5, None)]
    """
    if size < 1:
        raise ValueError(f"size: expected at least 1 sample per chunk, got {size}")
    if n < 0:
        raise ValueError(f"n: expected a sample count >= 0, got {n}")
    for a in range(0, n, size):
        yield slice(a, min(a + size, n))


def _check_chunk(X: np.ndarray, y: np.ndarray, p: int) -> tuple[np.ndarray, np.ndarray]:
    X, y = np.asarray(X, float), np.asarray(y, float)
    if X.ndim != 2 or X.shape[0] != p:
        raise ValueError(f"X: expected regressor rows of shape ({p}, m), got {X.shape}")
    if y.shape != (X.shape[1],):
        raise ValueError(f"y: expected {X.shape[1]} outputs (one per column of X), got "
                         f"shape {y.shape}")
    return X, y


class NormalEquations:
    """``G = sum X X^T`` and ``g = sum X y`` over chunks, solved with columns scaled to unit norm.

    Parameters
    ----------
    p : int
        Regressors (rows of each chunk).

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> X, y = rng.normal(size=(3, 50)), rng.normal(size=50)
    >>> ne = NormalEquations(3)
    >>> for s in chunks(50, 16):
    ...     ne.add(X[:, s], y[s])
    >>> bool(np.allclose(ne.solve(), np.linalg.lstsq(X.T, y, rcond=None)[0]))
    True
    """

    def __init__(self, p: int):
        if p < 1:
            raise ValueError(f"p: expected at least 1 regressor, got {p}")
        self.G = np.zeros((p, p))
        self.g = np.zeros(p)
        self.samples = 0
        self.yy = 0.0  # sum y^2, for rss(); NaN once a chunk came without it

    def add(self, X: np.ndarray, y: np.ndarray) -> None:
        """Add the samples of one chunk.

        Parameters
        ----------
        X : numpy.ndarray
            Regressors as rows, shape (p, m).
        y : numpy.ndarray
            Outputs, shape (m,).

        Raises
        ------
        ValueError
            Shapes that do not fit ``p`` or each other.
        """
        X, y = _check_chunk(X, y, self.g.size)
        self.G += X @ X.T
        self.g += X @ y
        self.samples += y.size
        self.yy += float(y @ y)

    def add_gram(self, G: np.ndarray, g: np.ndarray, samples: int,
                 yy: float | None = None) -> None:
        """Add sums ``X X^T`` and ``X y`` formed elsewhere (by blocks of regressors).

        Parameters
        ----------
        G : numpy.ndarray
            Shape (p, p).
        g : numpy.ndarray
            Shape (p,).
        samples : int
            Samples they sum over.
        yy : float or None
            ``y^T y`` of the same samples; None: not known (:meth:`rss` then gives None).
        """
        self.G += G
        self.g += g
        self.samples += samples
        self.yy += float("nan") if yy is None else yy

    def solve(self, rcond: float = 1e-13) -> np.ndarray:
        """The least-squares coefficients (columns scaled to unit norm for the solve).

        Parameters
        ----------
        rcond : float
            Relative cut-off of the singular values of the scaled ``G``.

        Returns
        -------
        numpy.ndarray
            Shape (p,); coefficients of columns that are all zero are 0.
        """
        d = np.sqrt(np.diag(self.G))
        d[d == 0] = 1.0
        c, *_ = np.linalg.lstsq(self.G / d[:, None] / d[None, :], self.g / d, rcond=rcond)
        return c / d

    def rss(self, coef: np.ndarray, rtol: float = RSS_RTOL) -> float | None:
        """The residual sum of squares ``sum (y - X^T coef)^2`` from the sums alone,
        ``y^T y - 2 coef^T g + coef^T G coef``, when it is safe from cancellation.

        The sums carry rounding errors of about ``eps (|coef|^T d + |y|)^2`` (``d`` the column
        norms, ``sqrt(diag G)``; Cauchy-Schwarz bounds ``|coef|^T |X| |X|^T |coef|`` by
        ``(|coef|^T d)^2``), which the subtraction keeps while the RSS itself may be many orders
        smaller (a good fit). The value is returned only when ``RSS_SAFETY`` times that estimate
        (times the square root of the chunks summed) is within ``rtol`` of the RSS; else None,
        and the caller makes a pass over the residuals. Measured on the diagnosis' fits, the
        value differs from the pass by at most 1.5 estimates (tests/test_diagnosis_chunked.py
        holds it within ``rtol`` of the exact RSS on ill-conditioned problems).

        Parameters
        ----------
        coef : numpy.ndarray
            Coefficients, shape (p,) (usually :meth:`solve`'s).
        rtol : float
            Largest relative error accepted.

        Returns
        -------
        float or None
            The RSS over every sample added, or None (not safe, or ``y^T y`` not known).

        Examples
        --------
        >>> rng = np.random.default_rng(2)
        >>> X, y = rng.normal(size=(3, 40)), rng.normal(size=40)
        >>> ne = NormalEquations(3)
        >>> ne.add(X, y)
        >>> c = ne.solve()
        >>> bool(np.isclose(ne.rss(c), np.sum((y - c @ X) ** 2), rtol=1e-12, atol=0))
        True
        """
        if not np.isfinite(self.yy):
            return None
        d = np.sqrt(np.diag(self.G))
        scale = float(np.abs(coef) @ d) + np.sqrt(self.yy)
        rss = self.yy - 2.0 * float(coef @ self.g) + float(coef @ (self.G @ coef))
        rounding = RSS_SAFETY * np.finfo(float).eps * scale * scale \
            * np.sqrt(max(1.0, self.samples / CHUNK))
        return float(rss) if rss > 0 and rounding <= rtol * rss else None


class ChunkedQR:
    """A running triangular factor ``R`` of ``[X^T | y]``: each chunk is stacked under it and
    factored again (Householder QR, LAPACK ``dgeqrf``), so the fit never forms ``X X^T``.

    Parameters
    ----------
    p : int
        Regressors (rows of each chunk).

    Examples
    --------
    >>> rng = np.random.default_rng(1)
    >>> X, y = rng.normal(size=(4, 70)), rng.normal(size=70)
    >>> qr = ChunkedQR(4)
    >>> for s in chunks(70, 32):
    ...     qr.add(X[:, s], y[s])
    >>> coef, rss = qr.solve()
    >>> ref, res, *_ = np.linalg.lstsq(X.T, y, rcond=None)
    >>> bool(np.allclose(coef, ref)), bool(np.isclose(rss, res[0]))
    (True, True)
    """

    def __init__(self, p: int):
        if p < 1:
            raise ValueError(f"p: expected at least 1 regressor, got {p}")
        self.p = p
        self.R = np.zeros((0, p + 1))
        self.samples = 0

    def add(self, X: np.ndarray, y: np.ndarray) -> None:
        """Add the samples of one chunk: regressors ``X`` as rows, shape (p, m), and outputs
        ``y``, shape (m,) (a ValueError for shapes that do not fit), as
        :meth:`NormalEquations.add` takes them; the factor is updated in place."""
        X, y = _check_chunk(X, y, self.p)
        if y.size == 0:  # a chunk whose samples are all masked (a long start-up left out)
            return
        k = self.R.shape[0]
        # the stack in column-major order, factored in place by LAPACK's dgeqrf: half the time
        # of numpy.linalg.qr on the row-major stack (measured: 33 against 65 ms for 16,466 x 82)
        A = np.empty((k + y.size, self.p + 1), order="F")
        A[:k] = self.R
        A[k:, :self.p] = X.T
        A[k:, self.p] = y
        qr, _, _, info = dgeqrf(A, overwrite_a=True)
        if info != 0:  # pragma: no cover - only for an illegal argument
            raise RuntimeError(f"ChunkedQR.add: LAPACK dgeqrf failed (info {info})")
        self.R = np.triu(qr[:min(qr.shape)])
        self.samples += y.size

    def solve(self, rcond: float = 1e-13) -> tuple[np.ndarray, float]:
        """The least-squares coefficients and the residual sum of squares.

        Parameters
        ----------
        rcond : float
            Relative cut-off of the singular values of the factor (rank-deficient columns).

        Returns
        -------
        coef : numpy.ndarray
            Shape (p,).
        rss : float
            ``sum (y - X^T coef)^2`` over every sample added.
        """
        R = self._square()
        coef, *_ = np.linalg.lstsq(R[:self.p, :self.p], R[:self.p, self.p], rcond=rcond)
        rest = R[:, self.p] - R[:, :self.p] @ coef
        return coef, float(rest @ rest)

    def solve_nonneg(self, nonneg: np.ndarray) -> np.ndarray:
        """The least-squares coefficients with some held at or above 0, from the factor.

        Bounded-variable least squares (``scipy.optimize.lsq_linear``, ``method="bvls"``) on
        ``R`` and its last column: the same objective as on the samples, up to a constant,
        with the condition number of ``X`` (not its square, as from :class:`NormalEquations`).

        Parameters
        ----------
        nonneg : numpy.ndarray
            Boolean mask, shape (p,) or shorter (the leading columns): the coefficients held
            at or above 0.

        Returns
        -------
        numpy.ndarray
            Shape (p,).

        Raises
        ------
        ValueError
            If ``nonneg`` is not a boolean vector of at most ``p`` entries.

        Examples
        --------
        >>> qr = ChunkedQR(2)
        >>> qr.add(np.array([[1.0, 0.0, 1.0], [1.0, 1.0, 0.0]]), np.array([1.0, -1.0, 2.0]))
        >>> np.round(qr.solve_nonneg(np.array([False, True])), 12).tolist()
        [1.5, 0.0]
        """
        mask = np.asarray(nonneg)
        if mask.dtype != bool or mask.ndim != 1 or mask.size > self.p:
            raise ValueError(f"nonneg: expected a boolean mask of at most p={self.p} entries, "
                             f"got {mask.dtype} of shape {mask.shape}")
        R = self._square()
        bounded = np.zeros(self.p, dtype=bool)
        bounded[:mask.size] = mask
        x = lsq_linear(R[:self.p, :self.p], R[:self.p, self.p],
                       bounds=(np.where(bounded, 0.0, -np.inf), np.inf), method="bvls").x
        return np.where(bounded, np.maximum(x, 0.0), x)  # BVLS may leave -1e-19 at a bound

    def _square(self) -> np.ndarray:
        """The factor padded with rows of zeros to shape (p + 1, p + 1)."""
        R = np.zeros((self.p + 1, self.p + 1))
        R[:self.R.shape[0]] = self.R[:self.p + 1]
        return R


def stack_rows(parts) -> np.ndarray:
    """The blocks of rows ``parts`` (each (p_i, N), any layout) stacked, C-contiguous
    (``np.vstack`` keeps a column-major layout when its inputs have one).

    Examples
    --------
    >>> stack_rows([np.zeros((1, 2)), np.ones((2, 2)).T]).tolist()
    [[0.0, 0.0], [1.0, 1.0], [1.0, 1.0]]
    """
    out = np.empty((sum(X.shape[0] for X in parts), parts[0].shape[1]))
    i = 0
    for X in parts:
        out[i:i + X.shape[0]] = X
        i += X.shape[0]
    return out


TRANSPOSE_BLOCK = 512  # samples per block of transposed (a block of 80 columns: 320 kB)


def transposed(M: np.ndarray) -> np.ndarray:
    """``M.T`` as a new C-contiguous array, copied a block of ``TRANSPOSE_BLOCK`` rows of ``M``
    at a time (the same values as ``np.ascontiguousarray(M.T)``: a copy, no arithmetic; each
    block stays in the cache, where one strided copy of a screen's columns to rows did not:
    about 1.7x faster on 65,536 x 33).

    Examples
    --------
    >>> transposed(np.arange(6.0).reshape(3, 2)).tolist()
    [[0.0, 2.0, 4.0], [1.0, 3.0, 5.0]]
    """
    out = np.empty(M.shape[::-1], dtype=M.dtype)
    for i in range(0, M.shape[0], TRANSPOSE_BLOCK):
        out[:, i:i + TRANSPOSE_BLOCK] = M[i:i + TRANSPOSE_BLOCK].T
    return out


def combine(P: tuple, coef: np.ndarray) -> np.ndarray:
    """``coef @ B`` for the rows ``B`` the blocks ``P`` stack (each block's product, summed
    in order).

    Examples
    --------
    >>> combine((np.ones((1, 2)), np.arange(2.0)[None]), np.array([2.0, 3.0])).tolist()
    [2.0, 5.0]
    """
    out, i = None, 0
    for X in P:
        term = coef[i:i + X.shape[0]] @ X
        out = term if out is None else out + term
        i += X.shape[0]
    return out
