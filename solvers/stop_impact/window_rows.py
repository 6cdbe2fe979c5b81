"""An LP assembled as sparse rows once and held in HiGHS, re-solved with only row bounds changed.

The synthesis' window LP (solvers/stop_impact/window_lp.py) is one matrix per phase angle and
sample set; the arrival window moves only which rows hold (their upper bound: a value, or +inf
where the row is masked). `Rows` collects the columns by name and the rows by family (each
`a x <= b`, or a tie `a x = b`), `HeldLP` rescales them, passes the model to HiGHS once and changes
the masked rows' bounds in place before each solve.

Scaling: the rows mix the spline's coefficients (S in [0, 1]), the lever's states (e ~ 1e-4 at
high lambda), the approach velocity [m/s] and the rebound's lines [mm per m/s]; their entries span
1e-8 ... 1e3. Rows and columns are divided by powers of two near the square root of their largest
entry, a few passes (Ruiz's equilibration, `equilibrate`): a power of two changes no digit, so the
scaled LP is the same LP and its solution maps back exactly.

Solves: HiGHS' dual simplex from scratch (the solver cleared before each window: the answer
depends on the window alone, not on those solved before it), the interior point where it does not
settle (SIMPLEX_OPTIONS, IPM_OPTIONS); both with iteration limits, never a clock. Status read
through `kit.highs.status_of`; nothing but kOptimal is SOLVED.
"""
import math

import highspy
import numpy as np
from scipy import sparse

from mechopt.kit import interrupt
from mechopt.kit.highs import InterruptibleHighs, RealHighs, status_of
from mechopt.kit.result import Status

__all__ = ["HeldLP", "Rows", "IPM_OPTIONS", "SIMPLEX_OPTIONS"]

INF = highspy.kHighsInf
# Each window from scratch (the solver cleared: the answer depends on the window alone, not on the
# windows solved before it): HiGHS' dual simplex after its presolve, on the rows as scaled here
# (its own scaling off: scaled twice, the dual simplex stalled on some infeasible windows, 4 s for
# 172 iterations, against 0.03 s). On the co-design's windows (24 coefficients x 5-8 speeds,
# 5000-8000 rows x 30 columns): 50-330 iterations, 0.04 s against 0.11 s for the interior point
# and 0.11 s for the dual simplex warm from the previous window (measured, benchmarks/synthesis.py).
# A window it does not settle within SIMPLEX_ITERATIONS, or leaves with no status, is retried by the
# interior point (crossover to a vertex), IPM_ITERATIONS at most, and only then given up (LIMIT).
SIMPLEX_ITERATIONS = 5_000      # 10x the most the scenes' windows take
IPM_ITERATIONS = 400            # 17-42 on the scenes' windows
SIMPLEX_OPTIONS = {"solver": "simplex", "simplex_iteration_limit": SIMPLEX_ITERATIONS, "simplex_scale_strategy": 0,
                   "output_flag": False}
IPM_OPTIONS = {"solver": "ipm", "run_crossover": "on", "ipm_iteration_limit": IPM_ITERATIONS, "output_flag": False}
SCALE_PASSES = 8                # Ruiz passes: each halves the distance (in powers of two) of a row's largest entry from 1
TINY = 1e-9                     # entries this small are dropped before and after scaling, as HiGHS drops them
                                # (small_matrix_value; after: the same LP HiGHS solves, without its warning)


class Rows:
    """Columns by name (each a block of `size`), rows by family: `le` rows `a x <= upper`, `tie`
    rows `a x = value`. A term is (column name, coefficients): a matrix (rows x the block's size,
    dense or sparse) or a vector (one entry a row, for a block of size 1)."""

    def __init__(self):
        self.columns, self.size = {}, 0
        self.col_lower, self.col_upper, self.cost = [], [], []
        self.blocks, self.upper, self.lower, self.family = [], [], [], []
        self.rows = 0

    def column(self, name, size=1, lower=-INF, upper=INF, cost=0.0):
        """A block of `size` columns; its first index."""
        self.columns[name] = (self.size, size)
        self.size += size
        for target, value in ((self.col_lower, lower), (self.col_upper, upper), (self.cost, cost)):
            target.append(np.broadcast_to(np.asarray(value, float), size))
        return self.columns[name][0]

    def bound(self, name, lower, upper):
        """New bounds on the block `name`'s columns (a trust region)."""
        size = self.columns[name][1]
        k = list(self.columns).index(name)             # one entry of col_lower per block, in order
        self.col_lower[k] = np.broadcast_to(np.asarray(lower, float), size)
        self.col_upper[k] = np.broadcast_to(np.asarray(upper, float), size)

    def le(self, family, terms, upper):
        """Rows `sum of terms <= upper` of `family`; their indices."""
        return self._add(family, terms, upper, -INF)

    def tie(self, terms, value):
        """Rows `sum of terms = value` (no family: never slackened)."""
        return self._add(None, terms, value, value)

    def _add(self, family, terms, upper, lower):
        m = None
        for name, coef in terms:
            start, size = self.columns[name]
            row, col, data, shape = _entries(coef)
            if shape[1] != size or (m is not None and shape[0] != m):
                raise ValueError(f"rows of {family}: a term on {name} has shape {shape}")
            m = shape[0]
            self.blocks.append((self.rows + row, start + col, data))
        self.upper.append(np.broadcast_to(np.asarray(upper, float), m))
        self.lower.append(np.broadcast_to(np.asarray(lower, float), m))
        self.family += [family] * m
        index = np.arange(self.rows, self.rows + m)
        self.rows += m
        return index

    def slacken(self, keep=("objective",)):
        """Each family but `keep` its own nonnegative slack column (`a x - s <= b`), cost 1 each:
        minimising their sum names the families that bind. The names of the slack columns."""
        names = []
        for family in dict.fromkeys(f for f in self.family if f is not None and f not in keep):
            rows = np.flatnonzero(np.array([f == family for f in self.family]))
            start = self.column(f"slack:{family}", lower=0.0, cost=1.0)
            self.blocks.append((rows, np.full(rows.size, start), -np.ones(rows.size)))
            names.append(family)
        return names

    def matrix(self):
        """The rows as a sparse matrix; entries of |a| <= TINY dropped (HiGHS drops them from the
        unscaled matrix it is given: scaled first, they would be kept, and the LP would change)."""
        rows, cols, data = (np.concatenate(parts) for parts in zip(*self.blocks))
        keep = np.abs(data) > TINY
        return sparse.csc_matrix((data[keep], (rows[keep], cols[keep])), shape=(self.rows, self.size))

    def bounds(self):
        """(row lower, row upper, column lower, column upper, cost) as arrays."""
        return tuple(np.concatenate(parts).astype(float) for parts in
                     (self.lower, self.upper, self.col_lower, self.col_upper, self.cost))


def _entries(coef):
    """(rows, columns, values, shape) of a term's nonzeros, row by row (a vector is a column): a
    dense array's by `nonzero`, as `coo_matrix` takes them, without building one."""
    if isinstance(coef, np.ndarray):
        dense = coef.reshape(-1, 1) if coef.ndim == 1 else coef
        row, col = np.nonzero(dense)
        return row, col, dense[row, col], dense.shape
    coo = sparse.coo_matrix(coef)
    return coo.row, coo.col, coo.data, coo.shape


def _power_of_two(x):
    return np.exp2(np.round(np.log2(x)))


def equilibrate(A, passes=SCALE_PASSES):
    """(row factors, column factors), powers of two, such that diag(r) A diag(s) has every row's and
    column's largest entry near 1 (Ruiz's passes: each row and column divided by the square root of
    its largest entry; Ruiz, A scaling algorithm to equilibrate both rows and columns norms in
    matrices, RAL-TR-2001-034). The scaled entries are the nonzeros times their factors (a power of
    two: exact), no matrix product."""
    A = abs(sparse.csr_matrix(A))
    A.sum_duplicates()
    filled = np.diff(A.indptr) > 0
    row, starts = np.repeat(np.arange(A.shape[0]), np.diff(A.indptr)), A.indptr[:-1][filled]
    r, s = np.ones(A.shape[0]), np.ones(A.shape[1])
    for _ in range(passes):
        data = A.data * r[row] * s[A.indices]
        rows, cols = np.zeros(A.shape[0]), np.zeros(A.shape[1])
        if data.size:
            rows[filled] = np.maximum.reduceat(data, starts)
            np.maximum.at(cols, A.indices, data)
        r /= _power_of_two(np.sqrt(np.where(rows > 0, rows, 1.0)))
        s /= _power_of_two(np.sqrt(np.where(cols > 0, cols, 1.0)))
    return r, s


def coefficient_range(A):
    """(smallest, largest) nonzero |entry| of a sparse matrix."""
    data = np.abs(sparse.csr_matrix(A).data)
    data = data[data > 0]
    return (float(data.min()), float(data.max())) if data.size else (0.0, 0.0)


class _HeldHighs(InterruptibleHighs):
    """HiGHS for the held LPs: run in the calling thread whatever the rows' count. The worker thread
    `InterruptibleHighs` gives an LP of THREADED_ROWS rows or more is for a presolve of seconds that
    polls no callback; these LPs' presolve takes milliseconds (well under a second at 10^3
    coefficients, 11,445 rows: measured) and their simplex and interior-point iterations call back,
    so Ctrl-C stops them within an iteration here too, without the thread's start and join on
    every window (~5 % of a co-design window LP's CPU, measured)."""

    def run(self):
        with interrupt.polled():
            return RealHighs.run(self)


class HeldLP:
    """`Rows` scaled and passed to HiGHS once; `solve(upper)` changes the upper bounds of the rows
    `movable` (unscaled values, +inf where a row is masked) and solves (module docstring)."""

    def __init__(self, rows: Rows, movable):
        A = rows.matrix()
        lower, upper, self.col_lower, self.col_upper, cost = rows.bounds()
        self.r, self.s = equilibrate(A)
        self.A = sparse.csc_matrix(A, copy=True)          # each entry times its row's and column's power of two
        self.A.data *= self.r[self.A.indices] * np.repeat(self.s, np.diff(self.A.indptr))
        self.A.data[np.abs(self.A.data) <= TINY] = 0.0      # what HiGHS would drop (and warn of): dropped here
        self.A.eliminate_zeros()
        self.columns, self.movable = rows.columns, np.asarray(movable, dtype=np.int32)
        self.row_lower, self.row_upper = self._scaled(lower, self.r), self._scaled(upper, self.r)
        self.cost = cost * self.s
        self.highs = _HeldHighs()
        self.highs.passModel(*self.arrays())
        self.iterations, self.retried = {}, 0

    def model(self):
        """The scaled LP as a HighsLp, with the movable rows' bounds as last set."""
        lp = highspy.HighsLp()
        lp.num_col_, lp.num_row_ = self.A.shape[1], self.A.shape[0]
        lp.col_cost_ = self.cost
        lp.col_lower_, lp.col_upper_ = self._cols(self.col_lower), self._cols(self.col_upper)
        lp.row_lower_, lp.row_upper_ = self.row_lower, self.row_upper
        lp.a_matrix_.format_ = highspy.MatrixFormat.kColwise
        lp.a_matrix_.start_, lp.a_matrix_.index_, lp.a_matrix_.value_ = self.A.indptr, self.A.indices, self.A.data
        return lp

    def arrays(self):
        """The scaled LP as `Highs.passModel`'s arrays (the same model as `model`, without a HighsLp's
        copies): columns, rows, nonzeros, column-wise, minimise, no offset, then the vectors."""
        A = self.A
        return (A.shape[1], A.shape[0], A.nnz, int(highspy.MatrixFormat.kColwise), int(highspy.ObjSense.kMinimize),
                0.0, self.cost, self._cols(self.col_lower), self._cols(self.col_upper), self.row_lower,
                self.row_upper, A.indptr.astype(np.int32), A.indices.astype(np.int32), A.data,
                np.zeros(A.shape[1], dtype=np.int32))           # every column continuous: an LP

    @staticmethod
    def _scaled(bound, factor):
        return np.where(np.isinf(bound), bound, bound * factor)

    def _cols(self, bound):
        return np.where(np.isinf(bound), bound, bound / self.s)

    def _options(self, options):
        for name, value in options.items():
            self.highs.setOptionValue(name, value)

    def set_upper(self, upper):
        """The movable rows' upper bounds [unscaled; +inf: the row does not hold]."""
        index = self.movable
        scaled = self._scaled(np.asarray(upper, float), self.r[index])
        self.row_upper[index] = scaled
        self.highs.changeRowsBounds(index.size, index, self.row_lower[index], scaled)

    def solve(self, upper):
        """(Status, x unscaled or None, objective value): the dual simplex from scratch; where it
        ends at its iteration limit or with no status, the interior point from scratch (counted in
        `retried`). Nothing but kOptimal is SOLVED."""
        self.set_upper(upper)
        status = self._run(SIMPLEX_OPTIONS)
        if status in (Status.LIMIT, Status.FAILED):
            self.retried += 1
            status = self._run(IPM_OPTIONS)
        if status is not Status.SOLVED:
            return status, None, math.inf
        x = np.asarray(self.highs.getSolution().col_value) * self.s
        return status, x, float(self.highs.getInfo().objective_function_value)

    def _run(self, options):
        self.highs.clearSolver()                    # from scratch: no basis or iterate of another window
        self._options(options)
        self.highs.run()
        info = self.highs.getInfo()
        self.iterations = {"ipm": info.ipm_iteration_count, "crossover": info.crossover_iteration_count,
                           "simplex": info.simplex_iteration_count}
        return status_of(self.highs)

    def block(self, x, name):
        """The block `name` of a solution vector."""
        start, size = self.columns[name]
        return x[start:start + size]
