"""Packed buffers and the named bundles the kernels see.

Every array of a world lives in a few flat buffers: per group one float64 buffer and one int64
buffer whose head is a layout table (per array: offset, then up to four dimensions). Python
keeps numpy views of the fields; a kernel call passes only the buffers (a numba call costs
~0.1 us per array argument) and the kernels carve them into named tuples here.

Groups: ``rods`` (model, state, control, work of all rods; rebuilt when rods are added),
``env`` (clamps, planes, drivers' per-rod copies and reactions; rebuilt when clamps, planes
or colliders change), ``cols`` (collider tables, per-query mesh caches; absent without
colliders, so plain worlds compile no mesh code).

The array lists below are the single source of truth: Python allocates from them, and each
``carve_*`` builds its tuple in the same order (``tests/test_bundles.py`` checks both agree).
"""

from __future__ import annotations

from collections import namedtuple

from numba import njit, types
from numba.core import cgutils
from numba.extending import intrinsic, overload
from numba.np.arrayobj import make_array, populate_array

from .banded import BLOCK_BAND

# Arrays of a group: (name, dtype "f" | "i", shape in symbolic dimensions, names of its rows
# or None, state: how many of its first rows (or 1: all of a single array) are state).
# Dimensions: R rods, N nodes, E elements, V Voronoi domains, S real segments, M real nodes,
# P node clamps, F frame clamps, D drivers, L planes, C colliders, Q query slots (N + E).
#
# The rods' fields are rows of a few stacked arrays (nodes, elements, Voronoi domains, rods;
# vectors, frames, scalars, integers): the kernels then pass ~17 arrays instead of ~70,
# which keeps numba's compile time down (it grows with every array of every signature).
# State rows come first in each stack: positions, velocities, frames, angular velocities;
# the stable integrator's step start, the state its last step ended in (second-order steps
# use the step before only if nothing changed the state since), predictor rates, viscous
# loads, contact planes and
# friction anchors, rod-rod contact offsets, the explicit integrator's start-inside offsets
# (nodes, segments),
# last step, contraction rate and contact count; the rod-rod
# Verlet list's reference positions and (pairs, valid, builds, touching).
ROD_ARRAYS = (
    ('n3', 'f', (16, 'N', 3), ('pos', 'vel', 'xn', 'vn', 'fn_el', 'ref', 'xe', 've', 'fext',
                              'force', 'contact_force', 'xp', 'extra', 'acc', 'xh', 'vh'), 8),
    ('e3', 'f', (13, 'E', 3), ('omega', 'wn', 'tn_el', 'we', 'J', 'inv_J', 'S', 'rest_sigma',
                              'text', 'torque', 'stress', 'alpha', 'wh'), 4),
    ('e33', 'f', (4, 'E', 3, 3), ('Q', 'Qn', 'Qe', 'Qh'), 3),
    ('v3', 'f', (6, 'V', 3), ('B', 'rest_kappa', 'kappa', 'couple', 'scr_C', 'scr_X'), 0),
    ('n1', 'f', (4, 'N'), ('pen_off', 'mass', 'node_radius', 'node_kmin'), 1),
    ('e1', 'f', (7, 'E'),
     ('pair_off', 'seg_off', 'rest_len', 'seg_radius', 'dil', 'scr_edot', 'scr_off'), 2),
    ('v1', 'f', (1, 'V'), ('rest_vor',), 0),
    ('r1', 'f', (11, 'R'), ('h_prev', 'rate', 'contacts', 'decay', 'nu', 'tau', 'times',
                            'coupled', 'fact_h', 'fact_age', 'first_upd'), 3),
    # The stable integrator's contact planes per query slot (see contact/speculative.py).
    ('sp_i', 'i', ('Q', 2, 5), None, 1),
    ('ei', 'i', (7, 'E'), ('seg_a', 'seg_b', 'seg_rod', 'seg_k', 'seg_ne', 'seg_closed',
                          'excluded'), 0),
    ('ri', 'i', (6, 'R'), ('node0', 'elem0', 'vor0', 'ne', 'closed', 'group'), 0),
    ('pair_state', 'i', (4,), None, 1),
    ('stats', 'f', ('R', 10), None, 0),
    ('sp_f', 'f', ('Q', 2, 21), None, 1),
    # Per element: contact stiffness blocks a-a, b-a, b-b (symmetric), then the friction's
    # coupling to the normal force a-a, a-b, b-a, b-b (nonsymmetric; row-column).
    ('el_K', 'f', ('E', 7, 3, 3), None, 0),
    ('status', 'i', ('R', 3), None, 0),
    ('segs', 'i', ('S',), None, 0),
    ('nodes', 'i', ('M',), None, 0),
    # The stable integrator's Newton system, per block (a rod's nodes and elements from
    # node0 + elem0; B = 0 for explicit worlds): matrix, residual, prescribed flags. Kept here
    # rather than allocated per call: ~8 us less per step() of a one-rod world.
    ('sys_A', 'f', ('B', 2 * BLOCK_BAND + 1, 3, 3), None, 0),
    ('sys_rhs', 'f', ('B', 3), None, 0),
    ('sys_fixed', 'i', ('B',), None, 0),
)
# Row indices of the stacked rod fields.
(N_POS, N_VEL, N_XN, N_VN, N_FN_EL, N_REF, N_XE, N_VE, N_FEXT, N_FORCE, N_CONTACT_FORCE,
 N_XP, N_EXTRA, N_ACC, N_XH, N_VH) = range(16)
(E_OMEGA, E_WN, E_TN_EL, E_WE, E_J, E_INV_J, E_S, E_REST_SIGMA, E_TEXT, E_TORQUE, E_STRESS,
 E_ALPHA, E_WH) = range(13)
E_Q, E_QN, E_QE, E_QH = 0, 1, 2, 3
V_B, V_REST_KAPPA, V_KAPPA, V_COUPLE, V_SCR_C, V_SCR_X = 0, 1, 2, 3, 4, 5
N_PEN_OFF, N_MASS, N_NODE_RADIUS, N_NODE_KMIN = 0, 1, 2, 3
E_PAIR_OFF, E_SEG_OFF, E_REST_LEN, E_SEG_RADIUS, E_DIL, E_SCR_EDOT, E_SCR_OFF = range(7)
V_REST_VOR = 0
R_H_PREV, R_RATE, R_CONTACTS, R_DECAY, R_NU, R_TAU, R_TIMES, R_COUPLED = 0, 1, 2, 3, 4, 5, 6, 7
# The stable integrator's Newton factor in the rod's rows of sys_A: the step it was made for
# (0: none, or changed since), its age in steps, the first update of the last step.
R_FACT_H, R_FACT_AGE, R_FIRST_UPD = 8, 9, 10
E_SEG_A, E_SEG_B, E_SEG_ROD, E_SEG_K, E_SEG_NE, E_SEG_CLOSED, E_EXCLUDED = 0, 1, 2, 3, 4, 5, 6
R_NODE0, R_ELEM0, R_VOR0, R_NE, R_CLOSED, R_GROUP = 0, 1, 2, 3, 4, 5
ENV = (
    # Clamps: rod ranges, clamped node / element, driver, offset in the driver frame (m),
    # rotation from the driver frame to the element's material frame (world-from-local).
    ("rod_pcon", "i", ("R1",), None, 0),
    ("rod_fcon", "i", ("R1",), None, 0),
    ("pcon_node", "i", ("P",), None, 0),
    ("pcon_drv", "i", ("P",), None, 0),
    ("pcon_off", "f", ("P", 3), None, 0),
    ("fcon_elem", "i", ("F",), None, 0),
    ("fcon_drv", "i", ("F",), None, 0),
    ("fcon_rel", "f", ("F", 3, 3), None, 0),
    ("planes", "f", ("L", 11), None, 0),
    # Drivers as each rod sees them during a call (rods run their steps independently),
    # the last step's reaction (force, torque about the driver's origin; world) and the
    # impulse since reset, per rod.
    ("dloc", "f", ("R", "D", 24), None, 0),
    ("dreact", "f", ("R", "D", 6), None, 0),
    ("dimp", "f", ("R", "D", 6), None, 0),
)
# Per query slot (node, then element; "Q"), but sized 0 where unused so that a snapshot does
# not copy them: mesh query caches ("QM": slots with a mesh collider, else 0) and friction
# anchors ("QA": slots with any collider, else 0).
COLS_STATE = (
    ("qc_meta", "i", ("QM", 5), None, 0),
    ("qc_geo", "f", ("QM", 8), None, 0),
    ("qc_tris", "i", ("QM", 32), None, 0),
    ("qc_dist", "f", ("QM", 32), None, 0),
    ("anchor", "f", ("QA", 4), None, 0),
    ("anchor_id", "i", ("QA",), None, 0),
)
COLS = (
    ("kind", "i", ("C",), None, 0),
    ("drv", "i", ("C",), None, 0),
    ("par", "f", ("C", 12), None, 0),
    ("rng", "i", ("C", 6), None, 0),
    ("allowed", "i", ("R", "C"), None, 0),
    ("pose", "f", ("R", "C", 4, 4), None, 0),
    ("twist", "f", ("R", "C", 6), None, 0),
    ("MV", "f", ("nv", 3), None, 0),
    ("MF", "i", ("nf", 3), None, 0),
    ("Blo", "f", ("nb", 3), None, 0),
    ("Bhi", "f", ("nb", 3), None, 0),
    ("Bleft", "i", ("nb",), None, 0),
    ("Bright", "i", ("nb",), None, 0),
    ("Bstart", "i", ("nb",), None, 0),
    ("Bcount", "i", ("nb",), None, 0),
    ("Border", "i", ("nf",), None, 0),
    ("Fn", "f", ("nf", 3), None, 0),
    ("En", "f", ("nf", 3, 3), None, 0),
    ("Vn", "f", ("nv", 3), None, 0),
    ("Fg", "f", ("nf", 3, 4), None, 0),
    ("tr_stack", "i", ("R", 64), None, 0),
    ("tr_bound", "f", ("R", 64), None, 0),
    ("pen", "f", ("N", "C"), None, 0),
    ("wrench", "f", ("R", "C", 6), None, 0),
)
COLS_STATE = tuple((n, k, s, r, 1) for n, k, s, r, _ in COLS_STATE)  # all of them state
GROUPS = {"rods": ROD_ARRAYS, "env": ENV, "cols": COLS_STATE + COLS}

Rods = namedtuple("Rods", [f[0] for f in ROD_ARRAYS])
Env = namedtuple("Env", [f[0] for f in ENV])
Colliders = namedtuple("Colliders", [f[0] for f in COLS_STATE + COLS])

# Driver table columns (one row per driver; world frame): position of the origin, rotation
# world-from-local (row-major), linear and angular velocity, linear and angular acceleration.
D_P, D_R, D_V, D_W, D_A, D_AL, D_COLS = 0, 3, 12, 15, 18, 21, 24


# ---------------------------------------------------------------- carving (numba side)
@intrinsic
def _borrow(typingctx, buf, offset, shape):
    """C-contiguous view of ``buf[offset:]`` with ``shape``, borrowed: it carries no meminfo,
    so creating, passing and dropping it costs no reference counting (a sliced and reshaped
    view costs two atomic operations at each, ~2 us per kernel call for a world's ~60 arrays).
    Valid while ``buf`` is, i.e. for the kernel call; never returned to Python."""
    if not (isinstance(buf, types.Array) and buf.ndim == 1 and buf.layout == "C"
            and isinstance(offset, types.Integer) and isinstance(shape, types.BaseTuple)
            and all(isinstance(d, types.Integer) for d in shape)):
        return None
    view = types.Array(buf.dtype, len(shape), "C")

    def codegen(context, builder, sig, args):
        src = make_array(sig.args[0])(context, builder, args[0])
        dims = [context.cast(builder, d, ty, types.intp)
                for d, ty in zip(cgutils.unpack_tuple(builder, args[2]), sig.args[2])]
        start = context.cast(builder, args[1], sig.args[1], types.intp)
        itemsize = context.get_constant(types.intp, context.get_abi_sizeof(
            context.get_data_type(view.dtype)))
        strides, stride = [], itemsize
        for d in reversed(dims):
            strides.insert(0, stride)
            stride = builder.mul(stride, d)
        out = make_array(view)(context, builder)
        populate_array(out, data=builder.gep(src.data, [start]), shape=dims, strides=strides,
                       itemsize=itemsize, meminfo=None)
        return out._getvalue()

    return view(buf, offset, shape), codegen


@njit(cache=True, inline="always")
def borrow(buf, offset, shape):
    """A C-contiguous ``shape`` view of the 1-D ``buf`` from ``offset`` without reference
    counting (passing counted views costs two atomic operations each time): the caller keeps
    ``buf`` alive while the view is used."""
    return _borrow(buf, offset, shape)


@njit(cache=True, inline="always")
def _f(F, L, k):
    return _borrow(F, L[k, 0], (L[k, 1],))


@njit(cache=True, inline="always")
def _f2(F, L, k):
    return _borrow(F, L[k, 0], (L[k, 1], L[k, 2]))


@njit(cache=True, inline="always")
def _f3(F, L, k):
    return _borrow(F, L[k, 0], (L[k, 1], L[k, 2], L[k, 3]))


@njit(cache=True, inline="always")
def _f4(F, L, k):
    return _borrow(F, L[k, 0], (L[k, 1], L[k, 2], L[k, 3], L[k, 4]))


@njit(cache=True, inline="always")
def _layout(I):
    return _borrow(I, 1, (I[0], 5))


@njit(cache=True, inline="always")
def carve_rods(F, I):
    """The rods group's arrays (see ``ROD_ARRAYS``)."""
    L = _layout(I)
    return Rods(_f3(F, L, 0), _f3(F, L, 1), _f4(F, L, 2), _f3(F, L, 3), _f2(F, L, 4),
                _f2(F, L, 5), _f2(F, L, 6), _f2(F, L, 7), _f3(I, L, 8), _f2(I, L, 9),
                _f2(I, L, 10), _f(I, L, 11), _f2(F, L, 12), _f3(F, L, 13), _f4(F, L, 14),
                _f2(I, L, 15), _f(I, L, 16), _f(I, L, 17), _f4(F, L, 18), _f2(F, L, 19),
                _f(I, L, 20))


@njit(cache=True, inline="always")
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
# damping and friction (negative: automatic), Verlet-list skin (m), time at the call's start,
# order of the stable integrator (1 backward Euler, 2 BDF2).
SIM_DT, SIM_G, SIM_MAX_STRAIN, SIM_TOL, SIM_RR, SIM_SKIN, SIM_T, SIM_ORDER, SIM_LEN = (
    0, 1, 4, 5, 6, 9, 10, 11, 12)
# opts: Newton iterations, load the drivers into the rods' copies first, store them back
# after, the range of rods to advance, and the call's outcome (the entry kernels' flag).
OPT_ITER, OPT_LOAD, OPT_STORE, OPT_R0, OPT_R1, OPT_FLAG, OPT_LEN = 0, 1, 2, 3, 4, 5, 6
