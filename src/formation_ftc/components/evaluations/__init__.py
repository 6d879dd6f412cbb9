"""Evaluation components: signals derived from each sample for records and metrics (one module per concept)."""
