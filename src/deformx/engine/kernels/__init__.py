"""Numba kernels over the packed arrays of a World (hot paths only)."""
