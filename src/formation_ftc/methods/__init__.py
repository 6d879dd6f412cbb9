"""Built-in generic methods (not tied to one paper). Importing registers them."""

from formation_ftc.methods import cw_formation  # noqa: F401
