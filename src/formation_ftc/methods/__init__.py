"""Built-in generic methods (not tied to one paper). Importing registers them."""

from formation_ftc.methods import composed  # noqa: F401
