"""Yang, Jiang, Cocquempot, Chen (2013): spacecraft formation stabilization and fault tolerance, a
state-varying switched system approach (Systems & Control Letters 62(9)). Registers method
``yang2013`` and reproduction ``yang2013``."""

from formation_ftc.papers.yang2013 import registration  # noqa: F401
