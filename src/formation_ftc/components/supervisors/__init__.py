"""Supervisors components (one module per concept)."""
