"""Entry kernels: one call per ``World.step(n)``, one per integrator and coupling.

They take only the world's buffers (a numba call costs ~0.1 us per array argument), carve
them into bundles (:mod:`.bundles`), advance the rods (together when they touch each other,
else each on its own) and the drivers. They leave the new time in ``sim[SIM_T]`` (one group
of rods; groups on threads leave it in the rods' ``times``) and a flag in ``opts[OPT_FLAG]``:
the first rod that diverged, -1 if none, -2 if none but a rod started deeper inside a
collider than a step resolves. They return None when the flag is -1 and the rod-rod pair list
did not grow, else the pair list (the one passed in, or a grown one to keep): the common
call then boxes no return value (a returned tuple cost ~0.6 us of a one-rod ``step()``).
"""

from __future__ import annotations

from numba import njit, typeof
from numba.core.typing.typeof import Purpose

from .bundles import (
    OPT_FLAG, OPT_LOAD, OPT_R0, OPT_R1, OPT_STORE, R_NE, R_TIMES, SIM_T, carve_cols,
    carve_env, carve_rods,
)
from .coupled import advance_world_implicit, advance_world_verlet
from .drivers import begin_step, end_step, load_drivers, store_drivers
from .implicit import advance_rods_implicit
from .verlet import OK, advance_rods


@njit(cache=True, inline="always", error_model="numpy")
def _finish(t, sim, opts, rd, env, cols, drv):
    """Drivers back from the rods' copies and the time into ``sim`` (one group: groups on
    threads leave both to the caller); ``opts[OPT_FLAG]``: the rod that failed first, else -2
    if a rod is found deep inside a collider or another rod (``stats[r, 5]``, ``stats[r,
    9]``, warned about in Python), else
    -1. Returns whether the caller must look (flag not -1)."""
    r0, r1 = opts[OPT_R0], opts[OPT_R1]
    bad = -1
    for r in range(r0, r1):
        if rd.status[r, 0] != OK and (bad < 0 or rd.status[r, 2] < rd.status[bad, 2]):
            bad = r
    if bad < 0:
        for r in range(r0, r1):
            if rd.stats[r, 5] != 0.0 or rd.stats[r, 9] != 0.0:
                bad = -2
                break
    if opts[OPT_STORE]:
        store_drivers(drv, env, cols, r0, r1)
        if bad < 0:  # a divergence leaves the call's start time (the error reports from it)
            sim[SIM_T] = t
    opts[OPT_FLAG] = bad
    return bad != -1


@njit(cache=True, nogil=True, error_model="numpy")
def step_verlet(n_steps, sim, opts, RF, RI, EF, EI, CF, CI, drv, pairs):
    """``n_steps`` explicit steps of rods that do not touch each other (each on its own, all
    its steps at once); see the module's docstring."""
    rd = carve_rods(RF, RI)
    env = carve_env(EF, EI)
    cols = carve_cols(CF, CI)
    advance_rods(opts[OPT_R0], opts[OPT_R1], n_steps, sim[SIM_T], sim, rd, env, cols, drv,
                 opts[OPT_LOAD] != 0)
    if _finish(rd.r1[R_TIMES][opts[OPT_R0]], sim, opts, rd, env, cols, drv):
        return pairs
    return None


@njit(cache=True, nogil=True, error_model="numpy")
def step_verlet_coupled(n_steps, sim, opts, RF, RI, EF, EI, CF, CI, drv, pairs):
    """``n_steps`` explicit steps of rods that touch each other (all rods, one step at a
    time); see the module's docstring."""
    rd = carve_rods(RF, RI)
    env = carve_env(EF, EI)
    cols = carve_cols(CF, CI)
    for r in range(rd.ri[R_NE].shape[0]):
        load_drivers(env.dloc[r], drv, r, env, cols)
    grown = advance_world_verlet(n_steps, sim[SIM_T], sim, rd, env, cols, pairs)
    look = _finish(rd.r1[R_TIMES][0], sim, opts, rd, env, cols, drv)
    if look or grown.shape[0] != pairs.shape[0]:
        return grown
    return None


@njit(cache=True, nogil=True, error_model="numpy")
def step_stable(n_steps, sim, opts, RF, RI, EF, EI, CF, CI, drv, pairs):
    """``n_steps`` stable (backward-Euler) steps of rods that do not touch each other;
    see the module's docstring."""
    rd = carve_rods(RF, RI)
    env = carve_env(EF, EI)
    cols = carve_cols(CF, CI)
    advance_rods_implicit(opts[OPT_R0], opts[OPT_R1], n_steps, sim[SIM_T], sim, opts, rd, env,
                          cols, drv, opts[OPT_LOAD] != 0)
    if _finish(rd.r1[R_TIMES][opts[OPT_R0]], sim, opts, rd, env, cols, drv):
        return pairs
    return None


@njit(cache=True, nogil=True, error_model="numpy")
def step_stable_coupled(n_steps, sim, opts, RF, RI, EF, EI, CF, CI, drv, pairs):
    """``n_steps`` stable steps of rods that touch each other; see the module's
    docstring."""
    rd = carve_rods(RF, RI)
    env = carve_env(EF, EI)
    cols = carve_cols(CF, CI)
    for r in range(rd.ri[R_NE].shape[0]):
        load_drivers(env.dloc[r], drv, r, env, cols)
    grown = advance_world_implicit(n_steps, sim[SIM_T], sim, opts, rd, env, cols, pairs)
    look = _finish(rd.r1[R_TIMES][0], sim, opts, rd, env, cols, drv)
    if look or grown.shape[0] != pairs.shape[0]:
        return grown
    return None


# (integrator, rods touch each other) -> entry kernel. A world compiles only the one it uses:
# one kernel with both paths would compile the rod-rod machinery for every world (~5 s cold).
KERNELS = {("verlet", False): step_verlet, ("verlet", True): step_verlet_coupled,
           ("stable", False): step_stable, ("stable", True): step_stable_coupled}


@njit(cache=True, error_model="numpy")
def collect_drivers(EF, EI, CF, CI, drv, n_rods) -> None:
    """After rods advanced on threads: the drivers back from their copies."""
    store_drivers(drv, carve_env(EF, EI), carve_cols(CF, CI), 0, n_rods)


@njit(cache=True, error_model="numpy")
def advance_drivers(drv, n_steps, dt) -> None:
    """Drivers of a world without rods: the same recursion as inside the rods' steps."""
    for _ in range(n_steps):
        begin_step(drv, dt)
        end_step(drv, dt)


def compiled_entry(kernel, args: tuple):
    """The compiled code of ``kernel`` for the types of ``args``, callable without numba's
    dispatch (which types every argument at each call: ~1 us of a one-rod ``step()``); the
    kernel itself where numba keeps no such entry. Only for calls with arguments of exactly
    these types."""
    try:
        return kernel.overloads[tuple(typeof(a, Purpose.argument) for a in args)].entry_point
    except (AttributeError, KeyError):
        return kernel
