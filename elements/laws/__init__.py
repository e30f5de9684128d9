"""Constitutive laws as numba kernels: one module per law, each an incremental update."""
