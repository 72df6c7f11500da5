"""numba option for kernels that run without reference counting.

numba keeps counting the array arguments of any function that calls something able to raise
(an allocation, or a numba function it does not inline): two atomic operations per array and
call. A rod step passes ~55 arrays and a mesh query ~20, so that counting cost up to a third of a
step. Functions compiled with ``NO_REFCOUNT`` (and, unless they say otherwise, everything they
call) skip it: the explicit step (``advance_rod``), the mesh and rod-rod searches, and the
stable integrator's steps (``implicit._advance_island``, which runs in work arrays its caller
allocated) with the contact, solver and driver calls they make per Newton iteration. Safe for
our kernels: they only borrow the caller's arrays for the duration of the call and allocate
nothing (numba refuses to compile an allocation without counting, so a
new allocation on such a path is a compile error, not a leak). ``_nrt`` is a private numba
option: without it the kernels compile with plain counting.

The world's arrays themselves are not counted anywhere: the entry kernels carve them as
borrowed views without a meminfo (``bundles._borrow``), so even functions that count (those
that allocate) pass them for free; only arrays allocated inside a call are counted there.
"""

from __future__ import annotations

from numba.core.cpu import CPUTargetOptions

NO_REFCOUNT: dict = {"_nrt": False} if hasattr(CPUTargetOptions, "_nrt") else {}
