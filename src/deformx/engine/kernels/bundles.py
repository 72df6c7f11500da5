"""Packed buffers and the named bundles the kernels see.

Every array of a world lives in a few flat buffers: per group one float64 buffer and one int64
buffer whose head is a layout table (per field: offset, then up to four dimensions), and for
the rods a (rows, 3) float buffer holding their many (n, 3) fields. Python keeps numpy views of
the fields; a kernel call passes only the buffers (a numba call costs ~0.1 us per array
argument) and the kernels carve them into named tuples here (~1 us for all of them).

Groups: ``rods`` (model, state, control, work of all rods; rebuilt when rods are added),
``env`` (clamps, planes, drivers' per-rod copies and reactions; rebuilt when clamps, planes
or colliders change), ``cols`` (collider tables, per-query mesh caches; absent without
colliders, so plain worlds compile no mesh code).

The field lists below are the single source of truth: Python allocates from them, and each
``carve_*`` builds its tuple in the same order (``tests/test_bundles.py`` checks both agree).
State fields come first in each group, so a state snapshot is a prefix copy.
"""

from __future__ import annotations

from collections import namedtuple

from numba import njit, types
from numba.extending import overload

# (name, dtype "f" | "i", shape in symbolic dimensions): R rods, N nodes, E elements,
# V Voronoi domains, S real segments, M real nodes, P node clamps, F frame clamps,
# D drivers, L planes, C colliders, Q query slots (N + E), and numbers.
ROD_STATE = (
    ("pos", "f", ("N", 3)), ("vel", "f", ("N", 3)), ("Q", "f", ("E", 3, 3)),
    ("omega", "f", ("E", 3)),
    # Stable integrator memory: step start, previous rates (predictor), viscous loads,
    # plane friction anchors and the active set, Newton's last step and contraction rate.
    ("xn", "f", ("N", 3)), ("vn", "f", ("N", 3)), ("Qn", "f", ("E", 3, 3)), ("wn", "f", ("E", 3)),
    ("fn_el", "f", ("N", 3)), ("tn_el", "f", ("E", 3)), ("anchor", "f", ("N", 3)),
    ("c_dir", "f", ("N", 3)), ("h_prev", "f", ("R",)), ("rate", "f", ("R",)),
    ("anchor_on", "i", ("N",)), ("c_plane", "i", ("N",)), ("c_stick", "i", ("N",)),
    # Rod-rod Verlet list: reference positions and (pairs, valid, builds, touching).
    ("ref", "f", ("N", 3)), ("pair_state", "i", (4,)),
)
ROD_MODEL = (
    ("node0", "i", ("R",)), ("elem0", "i", ("R",)), ("vor0", "i", ("R",)), ("ne", "i", ("R",)),
    ("closed", "i", ("R",)), ("group", "i", ("R",)),
    ("decay", "f", ("R",)), ("nu", "f", ("R",)), ("tau", "f", ("R",)),
    ("mass", "f", ("N",)), ("node_radius", "f", ("N",)), ("node_kmin", "f", ("N",)),
    ("J", "f", ("E", 3)), ("inv_J", "f", ("E", 3)), ("S", "f", ("E", 3)), ("rest_len", "f", ("E",)),
    ("rest_sigma", "f", ("E", 3)), ("B", "f", ("V", 3)), ("rest_vor", "f", ("V",)),
    ("rest_kappa", "f", ("V", 3)),
    # Segments (capsules) for rod-rod contact: nodes, rod, index along it, size, closed,
    # excluded neighbours, radius; the real segments and nodes (no ghosts).
    ("seg_a", "i", ("E",)), ("seg_b", "i", ("E",)), ("seg_rod", "i", ("E",)),
    ("seg_k", "i", ("E",)), ("seg_ne", "i", ("E",)), ("seg_closed", "i", ("E",)),
    ("excluded", "i", ("E",)), ("seg_radius", "f", ("E",)), ("segs", "i", ("S",)),
    ("nodes", "i", ("M",)),
)
ROD_CONTROL = (("fext", "f", ("N", 3)), ("text", "f", ("E", 3)))
ROD_WORK = (
    ("force", "f", ("N", 3)), ("contact_force", "f", ("N", 3)), ("torque", "f", ("E", 3)),
    ("dil", "f", ("E",)), ("stress", "f", ("E", 3)), ("kappa", "f", ("V", 3)),
    ("couple", "f", ("V", 3)), ("scr_C", "f", ("V", 3)), ("scr_X", "f", ("V", 3)),
    ("scr_edot", "f", ("E",)), ("el_K", "f", ("E", 3, 3, 3)), ("xp", "f", ("N", 3)),
    ("vp", "f", ("N", 3)), ("extra", "f", ("N", 3)), ("stats", "f", ("R", 5)),
    ("status", "i", ("R", 3)), ("times", "f", ("R",)),
)
ENV = (
    # Clamps: rod ranges, clamped node / element, driver, offset in the driver frame (m),
    # rotation from the driver frame to the element's material frame (world-from-local).
    ("rod_pcon", "i", ("R1",)), ("rod_fcon", "i", ("R1",)), ("pcon_node", "i", ("P",)),
    ("pcon_drv", "i", ("P",)), ("pcon_off", "f", ("P", 3)), ("fcon_elem", "i", ("F",)),
    ("fcon_drv", "i", ("F",)), ("fcon_rel", "f", ("F", 3, 3)),
    ("planes", "f", ("L", 11)),
    # Drivers as each rod sees them during a call (rods run their steps independently),
    # the last step's reaction (force, torque about the driver's origin; world) and the
    # impulse since reset, per rod.
    ("dloc", "f", ("R", "D", 24)), ("dreact", "f", ("R", "D", 6)), ("dimp", "f", ("R", "D", 6)),
)
COLS_STATE = (
    ("qc_meta", "i", ("Q", 5)), ("qc_geo", "f", ("Q", 7)), ("qc_tris", "i", ("Q", 32)),
    ("qc_dist", "f", ("Q", 32)), ("anchor", "f", ("Q", 4)), ("anchor_id", "i", ("Q",)),
)
COLS = (
    ("kind", "i", ("C",)), ("drv", "i", ("C",)), ("par", "f", ("C", 12)), ("rng", "i", ("C", 6)),
    ("allowed", "i", ("R", "C")), ("pose", "f", ("R", "C", 4, 4)), ("twist", "f", ("R", "C", 6)),
    ("MV", "f", ("nv", 3)), ("MF", "i", ("nf", 3)), ("Blo", "f", ("nb", 3)), ("Bhi", "f", ("nb", 3)),
    ("Bleft", "i", ("nb",)), ("Bright", "i", ("nb",)), ("Bstart", "i", ("nb",)),
    ("Bcount", "i", ("nb",)), ("Border", "i", ("nf",)), ("Fn", "f", ("nf", 3)),
    ("En", "f", ("nf", 3, 3)), ("Vn", "f", ("nv", 3)), ("Fg", "f", ("nf", 3, 4)),
    ("tr_stack", "i", ("R", 64)), ("tr_bound", "f", ("R", 64)), ("pen", "f", ("N", "C")),
    ("wrench", "f", ("R", "C", 6)),
)
GROUPS = {"rods": ROD_STATE + ROD_MODEL + ROD_CONTROL + ROD_WORK, "env": ENV,
          "cols": COLS_STATE + COLS}

STATE_FIELDS = {"rods": len(ROD_STATE), "env": 0, "cols": len(COLS_STATE)}

RodState = namedtuple("RodState", [f[0] for f in ROD_STATE])
RodModel = namedtuple("RodModel", [f[0] for f in ROD_MODEL])
RodControl = namedtuple("RodControl", [f[0] for f in ROD_CONTROL])
RodWork = namedtuple("RodWork", [f[0] for f in ROD_WORK])
Env = namedtuple("Env", [f[0] for f in ENV])
Colliders = namedtuple("Colliders", [f[0] for f in COLS_STATE + COLS])

# Driver table columns (one row per driver; world frame): position of the origin, rotation
# world-from-local (row-major), linear and angular velocity, linear and angular acceleration.
D_P, D_R, D_V, D_W, D_A, D_AL, D_COLS = 0, 3, 12, 15, 18, 21, 24


# ---------------------------------------------------------------- carving (numba side)
@njit(cache=True, inline="always")
def _f(F, L, k):
    o = L[k, 0]
    return F[o:o + L[k, 1]]


@njit(cache=True, inline="always")
def _f2(F, L, k):
    o = L[k, 0]
    return F[o:o + L[k, 1] * L[k, 2]].reshape((L[k, 1], L[k, 2]))


@njit(cache=True, inline="always")
def _f3(F, L, k):
    o = L[k, 0]
    return F[o:o + L[k, 1] * L[k, 2] * L[k, 3]].reshape((L[k, 1], L[k, 2], L[k, 3]))


@njit(cache=True, inline="always")
def _f4(F, L, k):
    o = L[k, 0]
    return F[o:o + L[k, 1] * L[k, 2] * L[k, 3] * L[k, 4]].reshape(
        (L[k, 1], L[k, 2], L[k, 3], L[k, 4]))


@njit(cache=True, inline="always")
def _layout(I):
    n = I[0]
    return I[1:1 + 5 * n].reshape((n, 5))


@njit(cache=True, inline="always")
def _s(buf, L, k):
    o = L[k, 0]
    return buf[o:o + L[k, 1]]


@njit(cache=True)
def carve_rods(F, I, F3):
    """(state, model, control, work) of the rods group: its (n, 3) float fields are slices of
    ``F3`` (slicing is ~7x cheaper than reshaping, and this runs on every call)."""
    L = _layout(I)
    state = RodState(_s(F3, L, 0), _s(F3, L, 1), _f3(F, L, 2), _s(F3, L, 3), _s(F3, L, 4),
        _s(F3, L, 5), _f3(F, L, 6), _s(F3, L, 7), _s(F3, L, 8), _s(F3, L, 9), _s(F3, L, 10),
        _s(F3, L, 11), _s(F, L, 12), _s(F, L, 13), _s(I, L, 14), _s(I, L, 15), _s(I, L, 16),
        _s(F3, L, 17), _s(I, L, 18))
    model = RodModel(_s(I, L, 19), _s(I, L, 20), _s(I, L, 21), _s(I, L, 22), _s(I, L, 23), _s(I,
        L, 24), _s(F, L, 25), _s(F, L, 26), _s(F, L, 27), _s(F, L, 28), _s(F, L, 29), _s(F, L,
        30), _s(F3, L, 31), _s(F3, L, 32), _s(F3, L, 33), _s(F, L, 34), _s(F3, L, 35), _s(F3, L,
        36), _s(F, L, 37), _s(F3, L, 38), _s(I, L, 39), _s(I, L, 40), _s(I, L, 41), _s(I, L,
        42), _s(I, L, 43), _s(I, L, 44), _s(I, L, 45), _s(F, L, 46), _s(I, L, 47), _s(I, L, 48))
    control = RodControl(_s(F3, L, 49), _s(F3, L, 50))
    work = RodWork(_s(F3, L, 51), _s(F3, L, 52), _s(F3, L, 53), _s(F, L, 54), _s(F3, L, 55),
        _s(F3, L, 56), _s(F3, L, 57), _s(F3, L, 58), _s(F3, L, 59), _s(F, L, 60), _f4(F, L, 61),
        _s(F3, L, 62), _s(F3, L, 63), _s(F3, L, 64), _f2(F, L, 65), _f2(I, L, 66), _s(F, L, 67))
    return state, model, control, work


@njit(cache=True)
def carve_env(F, I):
    L = _layout(I)
    return Env(_f(I, L, 0), _f(I, L, 1), _f(I, L, 2), _f(I, L, 3), _f2(F, L, 4), _f(I, L, 5),
               _f(I, L, 6), _f3(F, L, 7), _f2(F, L, 8), _f3(F, L, 9), _f3(F, L, 10),
               _f3(F, L, 11))


@njit(cache=True)
def _carve_cols(F, I):
    L = _layout(I)
    return Colliders(
        _f2(I, L, 0), _f2(F, L, 1), _f2(I, L, 2), _f2(F, L, 3), _f2(F, L, 4), _f(I, L, 5),
        _f(I, L, 6), _f(I, L, 7), _f2(F, L, 8), _f2(I, L, 9), _f2(I, L, 10), _f4(F, L, 11),
        _f3(F, L, 12), _f2(F, L, 13), _f2(I, L, 14), _f2(F, L, 15), _f2(F, L, 16), _f(I, L, 17),
        _f(I, L, 18), _f(I, L, 19), _f(I, L, 20), _f(I, L, 21), _f2(F, L, 22), _f3(F, L, 23),
        _f2(F, L, 24), _f3(F, L, 25), _f2(I, L, 26), _f2(F, L, 27), _f2(F, L, 28),
        _f3(F, L, 29))

def carve_cols(F, I):
    """The colliders' tables, or None without colliders (decided when compiling, so a plain
    world compiles no collider code and a world with colliders sees no Optional type)."""


@overload(carve_cols, jit_options={"cache": True})
def _carve_cols_overload(F, I):
    if isinstance(F, types.NoneType):
        return lambda F, I: None
    return lambda F, I: _carve_cols(F, I)


# The run's scalars (float64 array ``sim``) and switches (int64 array ``opts``).
# sim: dt (s), gravity (m/s^2), max strain, Newton tolerance, rod-rod contact stiffness,
# damping and friction (negative: automatic), Verlet-list skin (m), time at the call's start.
SIM_DT, SIM_G, SIM_MAX_STRAIN, SIM_TOL, SIM_RR, SIM_SKIN, SIM_T, SIM_LEN = 0, 1, 4, 5, 6, 9, 10, 11
# opts: Newton iterations, rods touch each other (step together), load the drivers into the
# rods' copies first, store them back after, and the range of rods to advance.
OPT_ITER, OPT_COUPLED, OPT_LOAD, OPT_STORE, OPT_R0, OPT_R1, OPT_LEN = 0, 1, 2, 3, 4, 5, 6
