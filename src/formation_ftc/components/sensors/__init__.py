"""Sensors components (one module per concept)."""
