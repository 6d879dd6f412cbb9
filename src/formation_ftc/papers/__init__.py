"""Paper reproductions: one sub-package per paper; each registers its method(s) and reproduction."""
