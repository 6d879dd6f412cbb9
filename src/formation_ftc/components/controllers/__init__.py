"""Controllers components (one module per concept)."""
