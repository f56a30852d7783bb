"""Numba kernels: pure functions over flat arrays and scalars. No MPI, no config objects."""
