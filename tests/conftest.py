"""Shared test configuration: float64 JAX for every test."""

import formation_ftc  # noqa: F401  (enables jax_enable_x64)
