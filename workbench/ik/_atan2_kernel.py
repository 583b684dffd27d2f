r"""Compiled ``atan2`` over flat arrays, vectorised by LLVM: the batch's atan2 stage.

:func:`~workbench.ik.analytic_batch` computes every atan2 of a chunk of poses
in one call. ``numpy.arctan2`` is SIMD only where numpy has SVML (AVX-512);
elsewhere it calls libm once per element (about 28 ns), most of the batch's
time. :func:`atan2_into` is written without branches (every case a select)
so that LLVM vectorises its loop with the SIMD of any x86-64 or ARM machine.

Method (Cephes ``atan``, double precision): with ``mn ≤ mx`` the magnitudes
of ``y`` and ``x``, ``t = mn / mx`` in [0, 1]; above 0.66 the argument is
``(mn − mx) / (mn + mx)`` and π/4 is added. Cephes' rational approximation
``t + t z P(z) / Q(z)`` (``z = t²``) gives atan of the reduced argument; the
octant (``|y| > |x|``: π/2 − ·) and the half-plane (``x < 0`` or −0: π − ·)
add multiples of π/4 kept as a high and a low double, so that the result is
rounded once at the end; the sign is that of ``y``. Within 2 ulp of the
correctly rounded value (``tests/test_ik_closed_form.py`` checks it against
``numpy.arctan2``), with IEEE's special cases: NaN in gives NaN, ``(±0, ±0)``
and ``(±inf, ±inf)`` as C's ``atan2``.

Its own file: it is an entry point called from Python only, so Numba's cache
(which does not see changes in other files) has no caller to keep in step.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from workbench._compiled import entry_point

FloatArray = npt.NDArray[np.float64]

# Cephes atan.c: atan(t) = t + t z P(z) / Q(z), z = t², |t| <= 0.66.
_P0 = -8.750608600031904122785e-1
_P1 = -1.615753718733365076637e1
_P2 = -7.500855792314704667340e1
_P3 = -1.228866684490136173410e2
_P4 = -6.485021904942025371773e1
_Q0 = 2.485846490142306297962e1
_Q1 = 1.650270098316988542046e2
_Q2 = 4.328810604912902668951e2
_Q3 = 4.853903996359136964868e2
_Q4 = 1.945506571482613964425e2

#: π/4, π/2 and π as a double (exact multiples of each other) plus the rest.
_PIO4 = 0.78539816339744830962
_PIO4_LO = 3.061616997868382943065e-17
_PIO2 = 1.57079632679489661923
_PIO2_LO = 6.123233995736765886130e-17
_PI = 3.14159265358979323846
_PI_LO = 1.224646799147353177226e-16

#: 1 / 0.66: ``mn * _UPPER > mx`` (unlike ``mn > 0.66 * mx``, no ratio 1
#: of subnormals rounds below).
_UPPER = 1.0 / 0.66

#: Above it, the halves of mn and mx are exact and their sum cannot overflow.
_BIG = 1.0


@entry_point(outputs=("out",), contiguous=("y", "x"))
def atan2_into(y: FloatArray, x: FloatArray, out: FloatArray) -> None:
    """``out[i] = atan2(y[i], x[i])``, as ``numpy.arctan2`` to within 2 ulp.

    Args:
        y: (N,) C-contiguous, first arguments.
        x: (N,) C-contiguous, second arguments.
        out: (N,) output [rad], in [−π, π].
    """
    for i in range(y.shape[0]):
        yi, xi = y[i], x[i]
        ay, ax = abs(yi), abs(xi)
        both_inf = (ay == math.inf) & (ax == math.inf)
        ay = 1.0 if both_inf else ay
        ax = 1.0 if both_inf else ax
        swap = ay > ax
        mn = ax if swap else ay
        mx = ay if swap else ax
        upper = mn * _UPPER > mx  # t > 0.66: reduce around 1
        half = 0.5 if mx > _BIG else 1.0
        num = (mn - mx) * half if upper else mn
        den = mn * half + mx * half if upper else mx
        den = 1.0 if mx == 0.0 else den  # (±0, ±0): t = 0
        t = num / den
        z = t * t
        p = (((_P0 * z + _P1) * z + _P2) * z + _P3) * z + _P4
        q = ((((z + _Q0) * z + _Q1) * z + _Q2) * z + _Q3) * z + _Q4
        w = t + t * (z * p / q)
        # atan(mn / mx) = hi + lo + w
        hi = _PIO4 if upper else 0.0
        lo = _PIO4_LO if upper else 0.0
        # |y| > |x|: π/2 − atan(|x| / |y|) (π/2 − π/4 and π/2 − 0 are exact)
        hi = _PIO2 - hi if swap else hi
        lo = _PIO2_LO - lo if swap else lo
        w = -w if swap else w
        # x < 0 or −0: π − ·, with the rounding error of π − hi kept in lo
        negative = math.copysign(1.0, xi) < 0.0
        flipped = _PI - hi
        error = (_PI - flipped) - hi
        lo_flipped = _PI_LO - lo + error
        hi = flipped if negative else hi
        lo = lo_flipped if negative else lo
        w = -w if negative else w
        result = math.copysign(hi + (lo + w), yi)
        out[i] = yi + xi if (yi != yi) | (xi != xi) else result
