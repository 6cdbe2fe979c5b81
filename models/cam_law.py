"""A cam motion law as a spline in the rise's fraction xi, and the elastic follower's response to
it as a linear map of the spline's coefficients (Demeulenaere et al., ASME J. Mech.
Des. 131(10) 101004, 2009: a law linear in its coefficients makes the follower's response at a
fixed speed linear in them too).

The law S(xi) on [0, 1] is a clamped B-spline of degree p = continuity + 1 on uniform knots. The
dwell boundary conditions S = S' = S'' (= S''' for C3) = 0 at xi = 0 and S = 1, S' = S'' (= S''')
= 0 at xi = 1 fix the first and last continuity + 1 coefficients (0 and 1); the rest are free:

    S(xi) = s0(xi) + B(xi) c,         c the free coefficients.

The elastic follower of models/cam_follower.py, e'' + 2 zeta lambda e' + lambda^2 e = -S''(xi),
is linear and time-invariant in xi, so its response is the superposition of the responses to
each basis function's S''. On a uniform grid that holds every knot, a cubic's S'' is linear
between nodes and the first-order-hold step (augmented matrix exponential) is exact; a quartic's
errs by O(h^2). `elastic_response` gives (e, e') at the nodes for any number of inputs at once.

Models do no I/O and import no solver: `SplineLaw` is the finished law, `values(xi)` gives
S, S', S'', S''' on any xi grid (dwell and rest outside [0, 1]), `casadi_ddS(xi)` the CasADi
expression CVODES integrates (models/cam_follower.py `law_function`).
"""
from dataclasses import dataclass

import numpy as np

from mechopt.kit.errors import ModelError

CONTINUITIES = (2, 3)


def clamped_knots(intervals: int, degree: int) -> np.ndarray:
    """Clamped uniform knot vector on [0, 1]: `intervals` pieces, ends repeated degree + 1 times."""
    inner = np.linspace(0.0, 1.0, intervals + 1)
    return np.concatenate([np.zeros(degree), inner, np.ones(degree)])


def free_coefficient_count(intervals: int, continuity: int) -> int:
    """How many coefficients the dwell conditions leave free: intervals + p - 2 (continuity + 1)."""
    return intervals + continuity + 1 - 2 * (continuity + 1)


def intervals_for(coefficients: int, continuity: int) -> int:
    """The knot intervals that leave `coefficients` free coefficients."""
    return coefficients + continuity + 1


@dataclass(frozen=True)
class SplineBasis:
    """The rise's spline space: uniform knots, degree continuity + 1, dwell conditions imposed."""
    intervals: int
    continuity: int = 2

    def __post_init__(self):
        if self.continuity not in CONTINUITIES:
            raise ModelError(f"continuity={self.continuity}: allowed {CONTINUITIES} (C2 cubic, C3 quartic)",
                             key="continuity")
        if free_coefficient_count(self.intervals, self.continuity) < 1:
            raise ModelError(f"intervals={self.intervals}: too few for continuity C{self.continuity} "
                             f"(at least {self.continuity + 2})", key="coefficients")

    @property
    def degree(self) -> int:
        return self.continuity + 1

    @property
    def knots(self) -> np.ndarray:
        return clamped_knots(self.intervals, self.degree)

    @property
    def size(self) -> int:
        return free_coefficient_count(self.intervals, self.continuity)

    def full_coefficients(self, free) -> np.ndarray:
        """All B-spline coefficients: continuity + 1 zeros, the free ones, continuity + 1 ones."""
        fixed = self.continuity + 1
        return np.concatenate([np.zeros(fixed), np.asarray(free, float), np.ones(fixed)])

    def matrices(self, xi, order: int = 3):
        """[(s0, B)] for derivatives 0..order at `xi` in [0, 1]: S^(k)(xi) = s0_k + B_k c, B_k sparse
        (CSR: a row holds degree + 1 basis functions). The k-th derivative's basis is the degree
        p - k design matrix on the inner knots times the coefficients' scaled differences
        (de Boor), so no dense (points x coefficients) table is ever formed."""
        from scipy import sparse
        from scipy.interpolate import BSpline  # scipy's modules load where a spline law is used
        xi = np.clip(np.asarray(xi, float), 0.0, 1.0)
        t, p, fixed = self.knots, self.degree, self.continuity + 1
        count = t.size - p - 1
        to_derivative = sparse.identity(count, format="csr")    # coefficients of S^(k) from all of S's
        out = []
        for d in range(order + 1):
            deg = p - d
            if deg < 0:
                full = sparse.csr_matrix((xi.size, count))
            else:
                knots = t[d:t.size - d]
                full = (BSpline.design_matrix(xi, knots, deg) @ to_derivative).tocsr()
            if 0 < deg and d < order:
                n = to_derivative.shape[0]
                width = knots[deg + 1:deg + n] - knots[1:n]            # t_{i+deg+1} - t_{i+1}
                diff = sparse.diags([-np.ones(n - 1), np.ones(n - 1)], [0, 1], shape=(n - 1, n))
                to_derivative = (sparse.diags(deg / width) @ diff @ to_derivative).tocsr()
            offset = np.asarray(full[:, count - fixed:].sum(axis=1)).ravel()
            out.append((offset, full[:, fixed:count - fixed].tocsr()))
        return out

    def law(self, free, label: str = "synthesised") -> "SplineLaw":
        return SplineLaw(tuple(float(v) for v in self.knots), tuple(float(v) for v in self.full_coefficients(free)),
                         self.degree, label)


@dataclass(frozen=True)
class SplineLaw:
    """A finished motion law S(xi), a B-spline (knots, coefficients, degree); hashable, so the
    solvers' build caches and memoised chains key on it like on a library law's name."""
    knots: tuple
    coefficients: tuple
    degree: int
    label: str = "synthesised"

    def __str__(self):
        return f"{self.label} spline law (degree {self.degree}, {len(self.coefficients)} coefficients)"

    def _spline(self):
        from scipy.interpolate import BSpline
        return BSpline(np.asarray(self.knots), np.asarray(self.coefficients), self.degree, extrapolate=False)

    def values(self, xi):
        """(S, S', S'', S''') at `xi` (array): the rise on [0, 1], rest (S = 0) before it and the
        dwell (S = 1) after it, every derivative 0 outside.

        Examples
        --------
        >>> law = SplineBasis(8).law(np.linspace(0.1, 0.9, 5))
        >>> S, dS, ddS, dddS = law.values([0.0, 1.0, 1.5])
        >>> [round(float(v), 12) for v in S], [round(float(v), 12) for v in dS]
        ([0.0, 1.0, 1.0], [0.0, 0.0, 0.0])
        """
        xi = np.atleast_1d(np.asarray(xi, float))
        inside = np.clip(xi, 0.0, 1.0)
        spline = self._spline()
        parts = [spline(inside)] + [spline.derivative(d)(inside) for d in (1, 2, 3)]
        after, before = xi > 1.0, xi < 0.0
        parts[0] = np.where(after, 1.0, np.where(before, 0.0, parts[0]))
        return tuple(np.where(after | before, 0.0, np.nan_to_num(v)) if d else np.nan_to_num(v)
                     for d, v in enumerate(parts))

    def casadi_ddS(self, xi):
        """S''(xi) on [0, 1] as a CasADi SX expression: per knot interval a polynomial of degree
        p - 2 in (xi - left knot), its coefficients picked by `pw_const` (CVODES needs SX; CasADi's
        own BSpline node has no SX form)."""
        import casadi as ca  # here: a law used in a plan or a rebound needs no CasADi (a light `solve`)
        spline = self._spline().derivative(2)
        breaks = np.unique(np.asarray(self.knots))
        left = breaks[:-1]
        deg = self.degree - 2
        h = np.diff(breaks)
        # Taylor coefficients of S'' at each interval's left end, from its derivatives there
        taylor = [np.nan_to_num(spline.derivative(m)(left + 1e-14 * h) if m else spline(left + 1e-14 * h))
                  for m in range(deg + 1)]
        inner = ca.DM(breaks[1:-1])
        start = ca.pw_const(xi, inner, ca.DM(left))
        u = xi - start
        expr = 0
        for m in range(deg, -1, -1):                        # Horner
            coeff = ca.pw_const(xi, inner, ca.DM(taylor[m] / np.prod(np.arange(1, m + 1))))
            expr = expr * u + coeff
        return expr


def step_matrices(lam, zeta: float, h: float):
    """(Phi, Ga, Gb) of the first-order hold: y_{k+1} = Phi y_k + Ga u_k + Gb (u_{k+1} - u_k) / h
    for y = (e, e'), y' = [[0, 1], [-lam^2, -2 zeta lam]] y + [0, -1] u, u linear over the step.
    `lam` may be an array: one stacked matrix exponential for all (shapes (..., 2, 2), (..., 2))."""
    lam = np.asarray(lam, float)
    M = np.zeros(lam.shape + (4, 4))
    M[..., 0, 1], M[..., 1, 0], M[..., 1, 1], M[..., 1, 2], M[..., 2, 3] = 1.0, -lam * lam, -2.0 * zeta * lam, -1.0, 1.0
    E = small_expm(M * h)
    return E[..., :2, :2], E[..., :2, 2], E[..., :2, 3]


TAYLOR_DEGREE = 18          # terms of the scaled series: 0.25^19 / 19! ~ 1e-29, below any rounding


def small_expm(X):
    """exp of a stack of small matrices (..., n, n): the Taylor series on X / 2^s, its norm <= 1/4
    (s per matrix), squared s times (Moler & Van Loan, SIAM Review 45(1) 2003, methods 1 and 3), vectorised over
    the stack. scipy's expm takes 0.2 s for 33 4 x 4 matrices (its per-matrix norm estimates), this
    0.3 ms; the two agree to ~1e-15 of the largest entry (tests/stop_impact/test_law_synthesis.py)."""
    X = np.asarray(X, float)
    norm = np.abs(X).sum(axis=-1).max(axis=-1)                # each matrix's infinity norm
    s = np.where(norm > 0.25, np.ceil(np.log2(np.maximum(norm, 0.25) / 0.25)), 0).astype(int)
    Y = X / np.exp2(s)[..., None, None]
    E = np.broadcast_to(np.eye(X.shape[-1]), X.shape).copy()
    term = E.copy()
    for k in range(1, TAYLOR_DEGREE + 1):
        term = term @ Y / k
        E = E + term
    for i in range(int(s.max(initial=0))):                   # each matrix squared its own s times
        more = s > i
        E[more] = E[more] @ E[more]
    return E


def elastic_response(ddS, lam: float, zeta: float, h: float):
    """(e, e') at the nodes of a uniform grid of step h in xi (from rest at node 0) for each column
    of `ddS` (nodes x inputs): the follower's relative error driven by -S''. Linear in ddS."""
    ddS = np.asarray(ddS, float)
    flat = ddS.ndim == 1
    u = ddS[:, None] if flat else ddS
    Phi, Ga, Gb = step_matrices(lam, zeta, h)
    drive = Ga[:, None, None] * u[None, :-1] + Gb[:, None, None] * np.diff(u, axis=0)[None] / h
    out = np.zeros((2,) + u.shape)
    y = np.zeros((2, u.shape[1]))
    for k in range(u.shape[0] - 1):
        y = Phi @ y + drive[:, k]
        out[:, k + 1] = y
    e, de = (out[0, :, 0], out[1, :, 0]) if flat else (out[0], out[1])
    return e, de


def elastic_responses(ddS, lams, zeta: float, h: float):
    """(e, e') (speeds x nodes) of one input `ddS` (nodes) at several lambdas at once: the dense
    check's many speeds in one pass over the grid."""
    u = np.asarray(ddS, float)
    Phi, Ga, Gb = step_matrices(np.atleast_1d(lams), zeta, h)     # (K, 2, 2), (K, 2), (K, 2)
    drive = Ga[:, :, None] * u[None, None, :-1] + Gb[:, :, None] * (np.diff(u) / h)[None, None, :]   # (K, 2, N-1)
    out = np.zeros((Phi.shape[0], 2, u.size))
    y = np.zeros((Phi.shape[0], 2))
    for k in range(u.size - 1):
        y = np.einsum("kij,kj->ki", Phi, y) + drive[:, :, k]
        out[:, :, k + 1] = y
    return out[:, 0], out[:, 1]
