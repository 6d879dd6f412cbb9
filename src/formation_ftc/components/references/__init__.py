"""References components (one module per concept)."""
