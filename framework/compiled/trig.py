"""Sine and cosine of one angle at once, inlined into compiled kernels.

Forward kinematics takes a sine and a cosine per revolute joint at every evaluation: on a 6-joint arm that was a
tenth of a Levenberg-Marquardt iteration through libm's calls (24.6 ns per pair when the angles are independent,
as a chain's joint angles are; measured on this project's 2-core AMD EPYC), where the same pair computed inline
costs 9.0 ns — the calls cannot overlap, inline arithmetic can.

:func:`sincos` is fdlibm's (Sun Microsystems, 1993; the algorithm of most C libraries): the angle reduced by the
nearest multiple ``n`` of π/2 with π/2 split in two parts (Cody & Waite: ``n·p₁`` exact for ``|n| < 2²⁰``, the
reduced angle kept as a head and a tail), then fdlibm's minimax polynomials on ``[−π/4, π/4]`` (``__kernel_sin``,
``__kernel_cos``, error below one unit in the last place there), and the quadrant chosen without branches; an
angle near a multiple of π/2 (its reduced angle a tiny difference) is reduced again with π/2's next parts, as
fdlibm's ``__ieee754_rem_pio2`` does, so that small results keep their relative accuracy.
Beyond :data:`REDUCED` (and for NaN / inf) it calls libm. Against libm over ``[−10⁵, 10⁵]``: at most one unit in
the last place apart (``tests/test_trig.py``).
"""

from __future__ import annotations

from .native import internal
import numpy as np

#: Largest ``|x|`` reduced here (``n < 2²⁰``: ``n·p₁`` exact); beyond, and for NaN / inf, libm's functions.
REDUCED = 1.0e5

_INV_PIO2 = 6.36619772367581382433e-01  # 2/π
_PIO2_1 = 1.57079632673412561417e00  # the first 33 bits of π/2
_PIO2_1T = 6.07710050650619224932e-11  # π/2 − _PIO2_1
_PIO2_2, _PIO2_2T = 6.07710050630396597660e-11, 2.02226624879595063154e-21  # the next 33 bits, and the rest
_PIO2_3, _PIO2_3T = 2.02226624871116645580e-21, 8.47842766036889956997e-32
# fdlibm's __kernel_sin: sin(x) ≈ x + x³ (S1 + x² S2 + ... + x¹⁰ S6) on [−π/4, π/4]
_S1, _S2, _S3 = -1.66666666666666324348e-01, 8.33333333332248946124e-03, -1.98412698298579493134e-04
_S4, _S5, _S6 = 2.75573137070700676789e-06, -2.50507602534068634195e-08, 1.58969099521155010221e-10
# fdlibm's __kernel_cos: cos(x) ≈ 1 − x²/2 + x⁴ (C1 + x² C2 + ... + x¹⁰ C6) on [−π/4, π/4]
_C1, _C2, _C3 = 4.16666666666666019037e-02, -1.38888888888741095749e-03, 2.48015872894767294178e-05
_C4, _C5, _C6 = -2.75573143513906633035e-07, 2.08757232129817482790e-09, -1.13596475577881948265e-11


@internal(inline=True)
def sincos(x: float) -> tuple[float, float]:
    """``(sin x, cos x)`` [x in rad], within one unit in the last place of libm's (see the module)."""
    if not abs(x) <= REDUCED:  # (NaN too)
        return np.sin(x), np.cos(x)
    n = np.floor(x * _INV_PIO2 + 0.5)
    head = x - n * _PIO2_1  # exact
    w = n * _PIO2_1T
    y = head - w  # the reduced angle in [−π/4, π/4] (good to 85 bits), and below its tail t
    if abs(y) < abs(x) * 1.52587890625e-05:  # x near a multiple of π/2, 16 bits cancelled: π/2's next part
        t0 = head
        w = n * _PIO2_2
        head = t0 - w
        w = n * _PIO2_2T - ((t0 - head) - w)
        y = head - w
        if abs(y) < abs(x) * 1.7763568394002505e-15:  # 49 bits cancelled: the third
            t0 = head
            w = n * _PIO2_3
            head = t0 - w
            w = n * _PIO2_3T - ((t0 - head) - w)
            y = head - w
    t = (head - y) - w
    z = y * y
    v = z * y
    s = y - ((z * (0.5 * t - v * (_S2 + z * (_S3 + z * (_S4 + z * (_S5 + z * _S6))))) - t) - v * _S1)
    h = 0.5 * z
    u = 1.0 - h
    c = u + (((1.0 - u) - h) + (z * z * (_C1 + z * (_C2 + z * (_C3 + z * (_C4 + z * (_C5 + z * _C6))))) - y * t))
    q = int(n)  # quadrant: (sin, cos) = (s, c), (c, −s), (−s, −c), (−c, s)
    odd = (q & 1) != 0
    a = c if odd else s
    b = s if odd else c
    return a * (1 - (q & 2)), b * (1 - ((q + 1) & 2))
