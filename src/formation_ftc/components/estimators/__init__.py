"""Estimators components (one module per concept)."""
