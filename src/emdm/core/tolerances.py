"""Every named tolerance of emdm, once, with its meaning and unit.

The compiled kernels read these at compile time (numba freezes module-level numbers), so this
module is part of the kernel cache's key (:func:`emdm.core.jit._cache_folder`): a changed value
is never served from a stale cache.
"""

from __future__ import annotations

SINGULAR_RELATIVE = 1e-14
"""Planar arm: ``m <= SINGULAR_RELATIVE (sum l)^2`` counts as an exact singularity (the minors
are rounding); there ``Jm`` is the steepest one-sided ascent (docs/mathematics.md (21))."""

FACTOR_PIVOT = 1e-3
"""Spatial arm: smallest diagonal entry of the triangular factor ``R`` of ``Ja^T = Q R``
(relative to the largest row norm of ``Ja``) for which the manipulability gradient uses the
factor; nearer a singularity it takes the SVD. The factor's rounding is about ``eps`` relative to
``|R|`` (``Ja Ja^T`` is never formed), so ``m`` and ``Jm`` stay within a few ``eps`` of the exact
values above the cut-off too; below it the SVD keeps them finite at the singularity."""

RANK_TOL = 1e-12
"""Columns (or rows) count as independent when a pivot or 2x2 minor exceeds this, relative to
their size."""

FEASIBILITY_TOL = 1e-10
"""A feasibility kernel's point must satisfy ``A x = alpha b`` and ``G x <= h`` to this, relative
to the size of the terms."""

KKT_TOL = 1e-9
"""Largest relative KKT residual (stationarity, equality, complementarity) accepted as optimal."""

BOUND_TOL = 1e-12
"""Largest bound or row excess accepted in an answer (rad/s or m/s, absolute)."""

ACTIVE_TOL = 1e-9
"""The certificate counts a bound as active when ``|x_j - bound| <= ACTIVE_TOL (1 + |bound|)``, an
inequality row when ``h_i - G_i x <= ACTIVE_TOL (1 + |h_i|)``: only those get multipliers."""

AT_BOUND = 1e-12
"""The record's one definition of a joint at a bound (the ``active`` column, read by the report
and the playground): its command within ``AT_BOUND (1 + |bound|)`` rad/s of it."""

ERROR_FLOOR = 1e-9
"""Smallest ``||e||`` (m) in the slack weight ``w_S = c_S / ||e||``."""

STALL_BAND = 1e-3
"""A run that did not reach its goal has stalled from the state after which its task error stays
within this band (m) of its final error, for at least ``STALL_TIME``."""

STALL_TIME = 1.0
"""Shortest stall (s) that counts as one."""

CHATTER_SPEED = 0.05
"""A joint chatters where its command reverses sign from one step to the next, at least this
speed (rad/s) on both sides, for ``CHATTER_STEPS`` reversals in a row."""

CHATTER_STEPS = 6
"""Fewest reversals in a row that count as chattering."""

SLACK_USED = 1e-9
"""The task slack is in use on a command whose slack ``||delta||`` exceeds this (m/s)."""

NEAR_SINGULAR = 0.01
"""A state is near-singular when the smallest singular value of its task Jacobian, position rows
divided by the reach, is below this: the arm has lost almost all of one task direction."""

COINCIDE = 1e-9
"""Two runs coincide at a state where their joint angles differ by at most this (rad)."""

LAZY = 0.5
"""A row ``G_i x <= h_i`` with ``h_i >= LAZY * max_box G_i x`` (it keeps at least half its
right-hand side against the largest value the bounds allow) is solved lazily: left out of the
first solve and checked at its answer (``sim.rows.settle_rows``). Dimensionless."""
