"""Integration-method coefficients, kept as data.

This module holds nothing but coefficient tables (Butcher / Rosenbrock
tableaus) as module-level, read-only ``numpy.float64`` arrays wrapped in small
immutable :class:`typing.NamedTuple` records.  The steppers that consume them
live elsewhere; the exact scheme each table is meant for is spelled out below
so that a stepper can be written (and checked) against this text alone.

All indices in this module are **zero-based**: ``A[i, j]`` is the coefficient
of stage ``j`` in stage ``i``.  The literature (and Julia sources) are
one-based, so ``A[i, j]`` here is :math:`a_{i+1,j+1}` in the papers, and
``k[i]`` here is :math:`k_{i+1}`.  ``s`` denotes the number of stages, ``h``
the step size and ``y0`` the state at the start of the step.  Every problem is
assumed **autonomous**, ``y' = f(y)``; a time-dependent right-hand side must
be made autonomous by appending ``t`` to the state (``t' = 1``) unless the
stepper implements the optional time terms described below.

1. DOPRI5 -- Dormand-Prince 5(4), explicit, FSAL, 7 stages
-----------------------------------------------------------
Fields of :data:`DOPRI5` (an :class:`ExplicitRKTableau`): ``c`` (7,),
``A`` (7, 7), ``b`` (7,), ``b_err`` (7,), ``dense`` (7, 4).

Step (``i = 0..6``)::

    k[i] = f(y0 + h * sum_{j<i} A[i, j] * k[j])
    y1   = y0 + h * sum_i b[i] * k[i]             # 5th order, propagated
    err  = h * sum_i b_err[i] * k[i]               # = y1 - y1_hat

``A[6, :] == b`` and ``b[6] == 0`` (first-same-as-last): the argument of stage
6 is ``y1`` itself, so ``k[6] = f(y1)`` is the ``k[0]`` of the next step and
``y1`` does not depend on ``k[6]``.  ``b_err = b - b_hat`` where ``b_hat`` are
the weights of the embedded 4th-order solution ``y1_hat``; ``err`` is
therefore the (signed) local error estimate of the 4th-order solution,
``O(h**5)``.  Note that SciPy's ``RK45.E`` has the opposite sign
(``b_hat - b``); only ``abs(err)`` matters for step-size control.  ``c[i]``
equals the row sum of ``A[i, :]`` and is only needed for non-autonomous
problems (``k[i] = f(t0 + c[i] h, ...)``).

Dense output (4th-order continuous extension of Shampine, as used in the
Fortran DOPRI5 of Hairer & Wanner and in SciPy's RK45), for
``theta = (t - t0) / h`` in ``[0, 1]``, with ``P = dense``::

    y(t0 + theta*h) = y0 + h * sum_i k[i] * (P[i, 0]*theta    + P[i, 1]*theta**2
                                            + P[i, 2]*theta**3 + P[i, 3]*theta**4)

It needs all seven stages, i.e. ``k[6] = f(y1)`` (free because of FSAL).  At
``theta = 1`` it reproduces ``y1`` (``P.sum(axis=1) == b``); it is of order 4
(local interpolation error ``O(h**5)``).

Source: J. R. Dormand, P. J. Prince, "A family of embedded Runge-Kutta
formulae", J. Comput. Appl. Math. 6 (1980) 19-26 (``c``, ``A``, ``b``,
``b_hat``); dense output: L. F. Shampine, "Some practical Runge-Kutta
formulas", Math. Comp. 46 (1986) 135-150, in the form of E. Hairer,
S. P. Norsett, G. Wanner, *Solving ODEs I*, 2nd ed., Sec. II.6 (``dopri5.f``,
coefficients ``d1..d7`` = ``P[:, 3]``).  ``P[:, 1]`` and ``P[:, 2]`` follow
from expanding Hairer's Horner form exactly in rational arithmetic::

    y(theta) = y0 + theta*(dy + (1-theta)*(r3 + theta*(r4 + (1-theta)*r5)))
    dy = h sum b_i k_i,  r3 = h k_0 - dy,  r4 = dy - h k_6 - r3,  r5 = h sum d_i k_i

and agree exactly with ``scipy.integrate.RK45.P``.

2. RODAS5P -- Rosenbrock-Wanner 5(4), L-stable, stiffly accurate, 8 stages
------------------------------------------------------------------------------
Fields of :data:`RODAS5P` (a :class:`RosenbrockTableau`): ``gamma`` (float),
``a`` (8, 8), ``C`` (8, 8), ``c`` (8,), ``d`` (8,), ``H`` (3, 8).

These are the coefficients in the *transformed* (Hairer-Wanner, "Rodas")
formulation that OrdinaryDiffEq.jl uses (``RodasTableau``: ``A``, ``C``,
``gamma``, ``c``, ``d``, ``H``; its ``A`` is our ``a``).  With ``J = f'(y0)``
(exact or approximate Jacobian) and ``I`` the identity::

    W = I / (h*gamma) - J                     # one LU factorisation per step
    for i = 0..7:
        u_i  = y0 + sum_{j<i} a[i, j] * k[j]          # stage argument
        W k[i] = f(u_i) + sum_{j<i} (C[i, j] / h) * k[j]   (+ h*d[i]*df/dt)
    y1  = u_7 + k[7]          (= y0 + sum_{j<7} a[7, j] k[j] + k[7])
    err = k[7]                (= y1 - u_7)

The stages ``k`` are *not* multiplied by ``h`` again: they are increments of
``y`` (this is the transformed variable ``U = Gamma K`` of Hairer-Wanner).
The method is stiffly accurate: ``a[7, :] = a[6, :] + e_6`` and
``a[6, :] = a[5, :] + e_5``, so ``u_7`` is itself an embedded solution of
order 4 and ``y1 = u_7 + k[7]`` is the order-5 solution; the local error
estimate of OrdinaryDiffEq.jl is ``k[7]`` (no separate ``b`` / ``b_hat``
vectors are needed).  OrdinaryDiffEq.jl writes the same step as
``W' = J - I/(h gamma)``, ``k = W' \\ -(f(u_i) + h d_i f_t + sum C_ij/h k_j)``,
which is identical.

For a non-autonomous ``f(t, y)`` the stage function is evaluated at
``t0 + c[i]*h`` and the term ``h*d[i]*df/dt(t0, y0)`` is added to the right
hand side of stage ``i``.  Our problems are autonomous, so ``c`` and ``d``
are unused by the stepper and are stored for completeness only.  In the
untransformed form ``alpha = a @ Gamma`` and ``Gamma = inv(I/gamma - C)``
(with ``C`` strictly lower triangular as stored), one has ``c = alpha.sum(1)``
and ``d = Gamma.sum(1)`` (``d[0] = gamma``).

Dense output (order 4; "Rodas5P" interpolant of OrdinaryDiffEq.jl), for
``theta`` in ``[0, 1]``::

    h_r = sum_j H[r, j] * k[j]        for r = 0, 1, 2
    y(t0 + theta*h) = (1-theta)*y0
                      + theta*(y1 + (1-theta)*(h_0 + theta*(h_1 + theta*h_2)))

which is exactly ``y0`` at ``theta = 0`` and exactly ``y1`` at ``theta = 1``.
(Rodas4-type methods with a 2-row ``H`` drop the ``h_2`` term.)

Index convention: OrdinaryDiffEq.jl stores ``A`` as 8x8 and ``C`` as 8x7
(both 1-based, strictly lower); here ``C`` is padded to 8x8 with a zero last
column so that ``a[i, j]`` and ``C[i, j]`` line up with ``A[i+1, j+1]`` and
``C[i+1, j+1]`` of the Julia source and with :math:`a_{i+1,j+1}`,
:math:`c_{i+1,j+1}` of the paper.  ``H[r, j]`` is Julia's ``H[r+1, j+1]``.

Source: G. Steinebach, "Construction of Rosenbrock-Wanner method Rodas5P and
numerical benchmarks within the Julia Differential Equations package",
BIT Numer. Math. 63, 27 (2023), doi:10.1007/s10543-023-00967-x.  The numbers
(17-digit values as used in production) are taken from SciML/OrdinaryDiffEq.jl,
``lib/OrdinaryDiffEqRosenbrock/src/rosenbrock_tableaus.jl`` (function
``Rodas5PTableau``); the step and interpolation formulas were checked against
``rosenbrock_perform_step.jl`` (``perform_step!`` for ``RosenbrockCache`` /
``RosenbrockCombinedConstantCache``) and ``rosenbrock_interpolants.jl`` of the
same package.  (Some older revisions of that file passed ``c`` and ``d`` to
the ``RodasTableau`` constructor in swapped order; the values stored here are
assigned by meaning and are verified by the ``c = alpha.sum(1)``,
``d = Gamma.sum(1)`` identities above in ``tests/test_tableaus.py``.)

3. RODAS4P and RODAS4P2 -- Rosenbrock-Wanner 4(3), L-stable, stiffly accurate, 6 stages
-------------------------------------------------------------------------------------------
Same fields, same step and same interpolation formula as RODAS5P (section 2),
with ``s = 6``: ``a[5, :] = a[4, :] + e_4``, so ``u_5`` is the embedded
order-3 solution, ``y1 = u_5 + k[5]`` is of order 4 and ``err = k[5]``.  ``H``
has two rows (no ``h_2`` term); the dense output is of order 3.  Both keep
their order on the Prothero-Robinson problem (no order reduction for stiff
problems), which is what the "P" stands for.  Julia stores ``C`` as 6x5; it
is padded here with a zero last column, as for RODAS5P.

Sources: G. Steinebach, "Order-reduction of ROW-methods for DAEs and method
of lines applications", Preprint 1741, TU Darmstadt (1995) (Rodas4P), and
G. Steinebach, "Improvement of Rosenbrock-Wanner method RODASP", in
*Progress in Differential-Algebraic Equations II*, Springer (2020) 165-184
(Rodas4P2).  The numbers are those of ``Rodas4PTableau`` and
``Rodas4P2Tableau`` in the OrdinaryDiffEq.jl file named above; they are
checked by ``tests/test_tableaus.py`` (the ``c``/``d`` identities, orders 4
global, 3 embedded and 3 dense, L-stability).

All arrays are C-contiguous ``float64`` and flagged read-only.
"""

from __future__ import annotations

from .tableau_types import (  # noqa: F401
    ExplicitRKTableau,
    FloatArray,
    RosenbrockTableau,
    _frozen,
)
from .tableaus_rodas4 import (  # noqa: F401
    _RODAS4P2_A4,
    _RODAS4P_A4,
    RODAS4P,
    RODAS4P2,
)

__all__ = [
    "ExplicitRKTableau",
    "RosenbrockTableau",
    "DOPRI5",
    "RODAS5P",
    "RODAS4P",
    "RODAS4P2",
]


# ---------------------------------------------------------------------------
# Dormand-Prince 5(4)
# ---------------------------------------------------------------------------

_DOPRI5_B = [35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84, 0.0]


# b_hat (embedded 4th order): 5179/57600, 0, 7571/16695, 393/640,
# -92097/339200, 187/2100, 1/40.  Stored here as b - b_hat, exactly reduced.
_DOPRI5_B_ERR = [
    71 / 57600,
    0.0,
    -71 / 16695,
    71 / 1920,
    -17253 / 339200,
    22 / 525,
    -1 / 40,
]


DOPRI5 = ExplicitRKTableau(
    c=_frozen([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0, 1.0]),
    A=_frozen(
        [
            [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            [1 / 5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            [3 / 40, 9 / 40, 0.0, 0.0, 0.0, 0.0, 0.0],
            [44 / 45, -56 / 15, 32 / 9, 0.0, 0.0, 0.0, 0.0],
            [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729, 0.0, 0.0, 0.0],
            [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656, 0.0, 0.0],
            _DOPRI5_B,
        ]
    ),
    b=_frozen(_DOPRI5_B),
    b_err=_frozen(_DOPRI5_B_ERR),
    # Columns multiply theta, theta**2, theta**3, theta**4.
    dense=_frozen(
        [
            [
                1.0,
                -8048581381 / 2820520608,
                8663915743 / 2820520608,
                -12715105075 / 11282082432,
            ],
            [0.0, 0.0, 0.0, 0.0],
            [
                0.0,
                131558114200 / 32700410799,
                -68118460800 / 10900136933,
                87487479700 / 32700410799,
            ],
            [
                0.0,
                -1754552775 / 470086768,
                14199869525 / 1410260304,
                -10690763975 / 1880347072,
            ],
            [
                0.0,
                127303824393 / 49829197408,
                -318862633887 / 49829197408,
                701980252875 / 199316789632,
            ],
            [
                0.0,
                -282668133 / 205662961,
                2019193451 / 616988883,
                -1453857185 / 822651844,
            ],
            [
                0.0,
                40617522 / 29380423,
                -110615467 / 29380423,
                69997945 / 29380423,
            ],
        ]
    ),
    order=5,
    embedded_order=4,
    dense_order=4,
    fsal=True,
)


"""Dormand-Prince 5(4) pair with Shampine's 4th-order dense output."""


# ---------------------------------------------------------------------------
# Rodas5P (Steinebach 2023), transformed Rosenbrock form
# ---------------------------------------------------------------------------

_RODAS5P_A6 = [
    -7.502846399306121,
    2.561846144803919,
    -11.627539656261098,
    -0.18268767659942256,
    0.030198172008377946,
]


RODAS5P = RosenbrockTableau(
    gamma=0.21193756319429014,
    a=_frozen(
        [
            [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            [3.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            [2.849394379747939, 0.45842242204463923, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            [
                -6.954028509809101,
                2.489845061869568,
                -10.358996098473584,
                0.0,
                0.0,
                0.0,
                0.0,
                0.0,
            ],
            [
                2.8029986275628964,
                0.5072464736228206,
                -0.3988312541770524,
                -0.04721187230404641,
                0.0,
                0.0,
                0.0,
                0.0,
            ],
            [*_RODAS5P_A6, 0.0, 0.0, 0.0],
            [*_RODAS5P_A6, 1.0, 0.0, 0.0],
            [*_RODAS5P_A6, 1.0, 1.0, 0.0],
        ]
    ),
    C=_frozen(
        [
            [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            [-14.155112264123755, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            [-17.97296035885952, -2.859693295451294, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            [
                147.12150275711716,
                -1.41221402718213,
                71.68940251302358,
                0.0,
                0.0,
                0.0,
                0.0,
                0.0,
            ],
            [
                165.43517024871676,
                -0.4592823456491126,
                42.90938336958603,
                -5.961986721573306,
                0.0,
                0.0,
                0.0,
                0.0,
            ],
            [
                24.854864614690072,
                -3.0009227002832186,
                47.4931110020768,
                5.5814197821558125,
                -0.6610691825249471,
                0.0,
                0.0,
                0.0,
            ],
            [
                30.91273214028599,
                -3.1208243349937974,
                77.79954646070892,
                34.28646028294783,
                -19.097331116725623,
                -28.087943162872662,
                0.0,
                0.0,
            ],
            [
                37.80277123390563,
                -3.2571969029072276,
                112.26918849496327,
                66.9347231244047,
                -40.06618937091002,
                -54.66780262877968,
                -9.48861652309627,
                0.0,
            ],
        ]
    ),
    c=_frozen(
        [
            0.0,
            0.6358126895828704,
            0.4095798393397535,
            0.9769306725060716,
            0.4288403609558664,
            1.0,
            1.0,
            1.0,
        ]
    ),
    d=_frozen(
        [
            0.21193756319429014,
            -0.42387512638858027,
            -0.3384627126235924,
            1.8046452872882734,
            2.325825639765069,
            0.0,
            0.0,
            0.0,
        ]
    ),
    H=_frozen(
        [
            [
                25.948786856663858,
                -2.5579724845846235,
                10.433815404888879,
                -2.3679251022685204,
                0.524948541321073,
                1.1241088310450404,
                0.4272876194431874,
                -0.17202221070155493,
            ],
            [
                -9.91568850695171,
                -0.9689944594115154,
                3.0438037242978453,
                -24.495224566215796,
                20.176138334709044,
                15.98066361424651,
                -6.789040303419874,
                -6.710236069923372,
            ],
            [
                11.419903575922262,
                2.8879645146136994,
                72.92137995996029,
                80.12511834622643,
                -52.072871366152654,
                -59.78993625266729,
                -0.15582684282751913,
                4.883087185713722,
            ],
        ]
    ),
    order=5,
    embedded_order=4,
    dense_order=4,
)


"""Rodas5P (Steinebach 2023) in OrdinaryDiffEq.jl's transformed form."""


"""Rodas4P (Steinebach 1995) in OrdinaryDiffEq.jl's transformed form."""


"""Rodas4P2 (Steinebach 2020) in OrdinaryDiffEq.jl's transformed form."""
