"""Networks components (one module per concept)."""
