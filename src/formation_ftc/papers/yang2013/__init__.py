"""Yang, Jiang, Cocquempot, Chen (2013): spacecraft formation stabilization and fault tolerance, a
state-varying switched system approach (Systems & Control Letters 62(9)). Registers reproduction
``yang2013``, the theorem conditions of the ``switching`` supervisor and the paper's figures; the
scenarios are composed (:mod:`formation_ftc.components.supervisors.switching`)."""

from formation_ftc.papers.yang2013 import registration  # noqa: F401
