"""Mesh geometry for contact: closest-point kernels, a triangle BVH and inside/outside tests."""
