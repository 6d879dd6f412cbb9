"""Actuators components (one module per concept)."""
