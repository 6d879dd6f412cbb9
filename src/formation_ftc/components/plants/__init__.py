"""Plants components (one module per concept)."""
